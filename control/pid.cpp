// SPDX-License-Identifier: Apache-2.0
#include "control/pid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace weedspray::control {
namespace {

void require_finite(double value, const char* field) {
  if (!std::isfinite(value)) {
    throw std::invalid_argument(std::string("PidConfig.") + field + " must be finite");
  }
}

}  // namespace

Pid::Pid(const PidConfig& config) : config_(config) {
  require_finite(config.gains.kp, "gains.kp");
  require_finite(config.gains.ki, "gains.ki");
  require_finite(config.gains.kd, "gains.kd");
  require_finite(config.output_min, "output_min");
  require_finite(config.output_max, "output_max");
  require_finite(config.tracking_gain_per_s, "tracking_gain_per_s");
  require_finite(config.derivative_filter_s, "derivative_filter_s");
  if (!(config.output_min < config.output_max)) {
    throw std::invalid_argument("PidConfig.output_min must be below output_max");
  }
  if (config.tracking_gain_per_s < 0.0) {
    throw std::invalid_argument("PidConfig.tracking_gain_per_s must be >= 0");
  }
  if (config.derivative_filter_s < 0.0) {
    throw std::invalid_argument("PidConfig.derivative_filter_s must be >= 0");
  }
  reset();
}

void Pid::reset() noexcept {
  has_previous_ = false;
  integral_ = 0.0;
  filtered_derivative_ = 0.0;
  terms_ = PidTerms{};
  terms_.output = std::clamp(0.0, config_.output_min, config_.output_max);
}

void Pid::enable(double current_output, double setpoint, double measurement) noexcept {
  const double output = std::clamp(current_output, config_.output_min, config_.output_max);
  const double proportional = config_.gains.kp * (setpoint - measurement);
  integral_ = std::isfinite(proportional) ? output - proportional : output;
  filtered_derivative_ = 0.0;
  previous_measurement_ = measurement;
  has_previous_ = std::isfinite(measurement);
  terms_ = PidTerms{proportional, integral_, 0.0, output, output};
  enabled_ = true;
}

double Pid::update(double setpoint, double measurement, double dt_s) noexcept {
  if (!std::isfinite(setpoint) || !std::isfinite(measurement) || !std::isfinite(dt_s) ||
      dt_s <= 0.0) {
    return terms_.output;
  }
  if (!enabled_) {
    previous_measurement_ = measurement;
    has_previous_ = true;
    return terms_.output;
  }
  const PidGains& g = config_.gains;
  const double error = setpoint - measurement;

  // Derivative on the measurement: no kick when the set-point steps.
  double raw_derivative = 0.0;
  if (has_previous_) raw_derivative = -g.kd * (measurement - previous_measurement_) / dt_s;
  if (config_.derivative_filter_s > 0.0) {
    const double alpha = dt_s / (config_.derivative_filter_s + dt_s);
    filtered_derivative_ += alpha * (raw_derivative - filtered_derivative_);
  } else {
    filtered_derivative_ = raw_derivative;
  }
  previous_measurement_ = measurement;
  has_previous_ = true;

  const double proportional = g.kp * error;
  const double integral_step = g.ki * error * dt_s;
  double candidate_integral = integral_ + integral_step;
  double unsaturated = proportional + candidate_integral + filtered_derivative_;
  double output = std::clamp(unsaturated, config_.output_min, config_.output_max);

  if (config_.anti_windup == AntiWindup::kClamping) {
    // Integrate only if it does not drive the output further into saturation.
    const bool pushing_high = unsaturated > config_.output_max && integral_step > 0.0;
    const bool pushing_low = unsaturated < config_.output_min && integral_step < 0.0;
    if (pushing_high || pushing_low) {
      candidate_integral = integral_;
      unsaturated = proportional + candidate_integral + filtered_derivative_;
      output = std::clamp(unsaturated, config_.output_min, config_.output_max);
    }
  } else {
    candidate_integral += config_.tracking_gain_per_s * (output - unsaturated) * dt_s;
  }
  integral_ = candidate_integral;
  terms_ = PidTerms{proportional, integral_, filtered_derivative_, unsaturated, output};
  return output;
}

}  // namespace weedspray::control
