// SPDX-License-Identifier: Apache-2.0
#include "control/flow_feedback.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace weedspray::control {

namespace {

const FlowTrimConfig& validated(const FlowTrimConfig& config) {
  auto finite = [](double x) { return std::isfinite(x); };
  if (!finite(config.min_correction) || !finite(config.max_correction) ||
      !(config.min_correction > 0.0) || !(config.min_correction <= 1.0) ||
      !(config.max_correction >= 1.0)) {
    throw std::invalid_argument("FlowTrimConfig: need 0 < min_correction <= 1 <= max_correction");
  }
  if (!finite(config.time_constant_s) || !(config.time_constant_s > 0.0)) {
    throw std::invalid_argument("FlowTrimConfig.time_constant_s must be > 0");
  }
  if (!finite(config.min_observed_s) || !(config.min_observed_s >= 0.0)) {
    throw std::invalid_argument("FlowTrimConfig.min_observed_s must be >= 0");
  }
  if (!finite(config.min_requested_flow_l_per_min) || config.min_requested_flow_l_per_min <= 0.0) {
    throw std::invalid_argument("FlowTrimConfig.min_requested_flow_l_per_min must be > 0");
  }
  if (!finite(config.min_open_fraction) || config.min_open_fraction < 0.0 ||
      config.min_open_fraction > 1.0) {
    throw std::invalid_argument("FlowTrimConfig.min_open_fraction must be in [0, 1]");
  }
  if (!finite(config.max_pressure_error_fraction) || config.max_pressure_error_fraction <= 0.0) {
    throw std::invalid_argument("FlowTrimConfig.max_pressure_error_fraction must be > 0");
  }
  return config;
}

// Whether the meter over a window says anything about the lines' promise: finite, enough flow
// and open valves, the promise known, the pressure on its set-point.
bool window_usable(const FlowTrimConfig& c, const FlowTrimInput& in) noexcept {
  return std::isfinite(in.promised_l_per_min) && std::isfinite(in.measured_total_l_per_min) &&
         std::isfinite(in.open_fraction) && std::isfinite(in.pressure_error_fraction) &&
         std::isfinite(in.dt_s) && in.dt_s > 0.0 && in.promise_known &&
         in.promised_l_per_min >= c.min_requested_flow_l_per_min &&
         in.open_fraction >= c.min_open_fraction &&
         std::abs(in.pressure_error_fraction) <= c.max_pressure_error_fraction;
}

}  // namespace

FlowTrim::FlowTrim(const FlowTrimConfig& config)
    : config_(validated(config)),
      ratio_(config_, config_.time_constant_s, config_.min_observed_s) {}

double FlowTrim::update(const FlowTrimInput& window) noexcept {
  frozen_ = !window_usable(config_, window);
  ratio_.update(window);
  return correction();
}

double FlowTrim::correction() const noexcept {
  const double ratio = ratio_.ratio();
  // A meter that counted nothing gives ratio 0: the largest correction, as an integrator's
  // wind-up would (the meter's own fault is another alarm's business).
  if (!(ratio > 0.0)) return config_.max_correction;
  return std::clamp(1.0 / ratio, config_.min_correction, config_.max_correction);
}

double promised_flow_l_per_min(const NozzleLine& line, double duty_pct,
                               double pressure_mpa) noexcept {
  if (!(duty_pct > 0.0)) return 0.0;
  if (duty_pct >= 100.0) return held_open_flow_l_per_min(line, pressure_mpa);
  return flow_for_duty_l_per_min(line, duty_pct, pressure_mpa);
}

double trimmed_duty_pct(const NozzleLine& line, double duty_pct, double correction,
                        double pressure_mpa) noexcept {
  if (!(duty_pct > 0.0) || duty_pct >= 100.0 || !std::isfinite(correction)) return duty_pct;
  const double flow = flow_for_duty_l_per_min(line, duty_pct, pressure_mpa);
  return raw_duty_for_flow_pct(line, flow * correction, pressure_mpa);
}

bool FlowTrimWindows::tick(double dt_s, const FlowTrimTick& tick, double pulses_per_litre,
                           FlowTrimInput& out) noexcept {
  if (!started_) {
    started_ = true;
    start_pulses_ = tick.pulses;
    elapsed_s_ = 0.0;
    sums_ = {};
    return false;
  }
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return false;
  elapsed_s_ += dt_s;
  sums_.promised_l_per_min += tick.promised_l_per_min * dt_s;
  sums_.open_fraction += tick.open_fraction * dt_s;
  sums_.pressure_error_fraction =
      std::max(sums_.pressure_error_fraction, std::abs(tick.pressure_error_fraction));
  sums_.promise_known = sums_.promise_known && tick.promise_known;
  if (elapsed_s_ < window_s_ - 1e-9) return false;
  out.promised_l_per_min = sums_.promised_l_per_min / elapsed_s_;
  out.open_fraction = sums_.open_fraction / elapsed_s_;
  out.pressure_error_fraction = sums_.pressure_error_fraction;
  out.promise_known = sums_.promise_known;
  out.measured_total_l_per_min =
      pulses_per_litre > 0.0
          ? static_cast<double>(tick.pulses - start_pulses_) / pulses_per_litre / elapsed_s_ * 60.0
          : std::numeric_limits<double>::quiet_NaN();  // FlowTrim freezes
  out.dt_s = elapsed_s_;
  start_pulses_ = tick.pulses;
  elapsed_s_ = 0.0;
  sums_ = {};
  return true;
}

CalibrationRatio::CalibrationRatio(const FlowTrimConfig& window_rules, double time_constant_s,
                                   double min_observed_s)
    : window_rules_(window_rules),
      time_constant_s_(time_constant_s),
      min_observed_s_(min_observed_s) {
  if (!(time_constant_s > 0.0))
    throw std::invalid_argument("CalibrationRatio time_constant_s must be > 0");
  if (!(min_observed_s >= 0.0))
    throw std::invalid_argument("CalibrationRatio min_observed_s must be >= 0");
}

void CalibrationRatio::update(const FlowTrimInput& in) noexcept {
  if (!window_usable(window_rules_, in)) return;
  const double keep = std::exp(-in.dt_s / time_constant_s_);
  metered_ = metered_ * keep + in.measured_total_l_per_min * in.dt_s;
  promised_ = promised_ * keep + in.promised_l_per_min * in.dt_s;
  observed_s_ += in.dt_s;
}

}  // namespace weedspray::control
