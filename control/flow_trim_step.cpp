// SPDX-License-Identifier: Apache-2.0
#include "control/flow_trim_step.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace weedspray::control {

double PressureFilter::update(double pressure_mpa, double dt_s) noexcept {
  if (!started_) {
    started_ = true;
    value_ = pressure_mpa;
  } else {
    value_ += (1.0 - std::exp(-dt_s / time_constant_s_)) * (pressure_mpa - value_);
  }
  return value_;
}

FlowTrimStep::FlowTrimStep(const FlowTrimStepConfig& config)
    : config_(config),
      windows_(config.window_s),
      trim_(config.trim),
      calibration_ratio_(config.trim),
      pressure_(config.pressure_filter_s) {
  if (!(std::isfinite(config.window_s) && config.window_s > 0.0))
    throw std::invalid_argument("FlowTrimStepConfig.window_s must be > 0");
  if (!(std::isfinite(config.pressure_filter_s) && config.pressure_filter_s > 0.0))
    throw std::invalid_argument("FlowTrimStepConfig.pressure_filter_s must be > 0");
}

void FlowTrimStep::reset() noexcept {
  trim_.reset();
  windows_.reset();
  calibration_ratio_.reset();
}

const FlowTrimStepOutputs& FlowTrimStep::step(const FlowTrimStepInputs& in) noexcept {
  if (!in.spraying) {
    windows_.reset();
    pressure_.reset();
    out_.active = false;
  } else {
    const double pressure = pressure_.update(in.pressure_mpa, in.dt_s);
    FlowTrimTick tick;
    tick.pressure_error_fraction =
        in.setpoint_mpa > 0 ? (pressure - in.setpoint_mpa) / in.setpoint_mpa : 0.0;
    tick.pulses = in.pulses;
    const double correction = trim_.correction();
    const std::size_t nozzles = std::min(in.duty_pct.size(), in.lines.size());
    double open_sum = 0.0;
    for (std::size_t n = 0; n < nozzles; ++n) {
      double& duty = in.duty_pct[n];
      open_sum += duty / 100.0;
      if (duty >= 100 && !(in.lines[n].full_open_flow_l_per_min > 0)) tick.promise_known = false;
      // The trim moves duties only inside the calibrated band, never into the closed one.
      if (duty > 0 && duty < 100) {
        duty = std::clamp(
            trimmed_duty_pct(in.lines[n], duty, correction, in.compensation_pressure_mpa),
            in.min_duty_pct, in.max_duty_pct);
      }
      // The meter is read against what the lines promise at the duties commanded.
      tick.promised_l_per_min +=
          promised_flow_l_per_min(in.lines[n], duty, in.compensation_pressure_mpa);
    }
    tick.open_fraction = nozzles > 0 ? open_sum / static_cast<double>(nozzles) : 0.0;
    FlowTrimInput window;
    if (windows_.tick(in.dt_s, tick, in.pulses_per_litre, window)) {
      trim_.update(window);
      calibration_ratio_.update(window);
    }
    out_.active = !trim_.frozen();
  }
  out_.correction = trim_.correction();
  out_.calibration_ratio = calibration_ratio_.ratio();
  out_.calibration_ratio_known = calibration_ratio_.known();
  return out_;
}

}  // namespace weedspray::control
