// SPDX-License-Identifier: Apache-2.0
#include "control/spray_rate_law.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace weedspray::control {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

bool positive(double x) {
  return std::isfinite(x) && x > 0.0;
}

// Flow scale of a nozzle at pressure P relative to its calibration pressure (sqrt law);
// 1 when either pressure is unusable (no compensation rather than a wild one).
double pressure_scale(double pressure_mpa, double reference_mpa) noexcept {
  if (!positive(pressure_mpa) || !positive(reference_mpa)) return 1.0;
  return std::sqrt(pressure_mpa / reference_mpa);
}

}  // namespace

void validate(const SprayLawConfig& c) {
  require(positive(c.nominal_flow_l_per_min), "spray law: nominal_flow_l_per_min must be > 0");
  require(positive(c.nozzle_width_m), "spray law: nozzle_width_m must be > 0");
  require(positive(c.nominal_speed_m_per_s), "spray law: nominal_speed_m_per_s must be > 0");
  require(positive(c.max_density) && c.max_density <= 1.0,
          "spray law: max_density must be in (0, 1]");
  require(std::isfinite(c.decision_threshold) && c.decision_threshold >= 0.0 &&
              c.decision_threshold <= 1.0,
          "spray law: decision_threshold must be in [0, 1]");
  require(std::isfinite(c.min_duty_pct) && std::isfinite(c.max_duty_pct) && c.min_duty_pct >= 0.0 &&
              c.min_duty_pct < c.max_duty_pct && c.max_duty_pct <= 100.0,
          "spray law: need 0 <= min_duty_pct < max_duty_pct <= 100");
}

void validate(const NozzleLine& line) {
  require(positive(line.slope_l_per_min_per_pct), "nozzle line: slope must be > 0");
  require(std::isfinite(line.intercept_l_per_min), "nozzle line: intercept must be finite");
  require(positive(line.calibration_pressure_mpa),
          "nozzle line: calibration_pressure_mpa must be > 0");
  require(std::isfinite(line.full_open_flow_l_per_min) && line.full_open_flow_l_per_min >= 0.0,
          "nozzle line: full_open_flow_l_per_min must be >= 0 (0 = unknown)");
}

double nominal_dose_l_per_m2(const SprayLawConfig& c) noexcept {
  return c.nominal_flow_l_per_min / (60.0 * c.nozzle_width_m * c.nominal_speed_m_per_s);
}

double target_flow_l_per_min(const SprayLawConfig& c, double density,
                             double speed_m_per_s) noexcept {
  if (!std::isfinite(density) || !std::isfinite(speed_m_per_s) || speed_m_per_s <= 0.0) {
    return 0.0;
  }
  if (density <= 0.0 || density < c.decision_threshold) return 0.0;
  const double d = std::min(density, c.max_density);
  return 60.0 * d * c.nozzle_width_m * speed_m_per_s * nominal_dose_l_per_m2(c) / c.max_density;
}

double raw_duty_for_flow_pct(const NozzleLine& line, double flow_l_per_min,
                             double pressure_mpa) noexcept {
  const double scale = pressure_scale(pressure_mpa, line.calibration_pressure_mpa);
  const double flow_at_calibration = flow_l_per_min / scale;
  // Full-open rule against the lower of the calibrated and the pressure-scaled full-open flow:
  // below the calibration pressure the valve cannot give more anyway, and above it pressure
  // noise around the set-point must not flip a valve asked for its full flow into switching.
  if (line.full_open_flow_l_per_min > 0.0 &&
      flow_l_per_min >= line.full_open_flow_l_per_min * std::min(1.0, scale) * (1.0 - 1e-9)) {
    return 100.0;
  }
  return (flow_at_calibration - line.intercept_l_per_min) / line.slope_l_per_min_per_pct;
}

double clamp_duty_pct(const SprayLawConfig& c, double raw_duty_pct) noexcept {
  if (!std::isfinite(raw_duty_pct) || raw_duty_pct < c.min_duty_pct) return 0.0;
  if (raw_duty_pct > c.max_duty_pct) return 100.0;
  return raw_duty_pct;
}

double clamp_duty_for_flow_pct(const SprayLawConfig& c, double raw_duty_pct,
                               double target_flow_l_per_min) noexcept {
  if (!(target_flow_l_per_min > 0.0) || !std::isfinite(target_flow_l_per_min)) return 0.0;
  if (c.low_duty_policy == LowDutyPolicy::kRaiseToMin &&
      !(std::isfinite(raw_duty_pct) && raw_duty_pct >= c.min_duty_pct)) {
    return c.min_duty_pct;
  }
  return clamp_duty_pct(c, raw_duty_pct);
}

double flow_for_duty_l_per_min(const NozzleLine& line, double duty_pct,
                               double pressure_mpa) noexcept {
  if (!(duty_pct > 0.0)) return 0.0;
  return (line.slope_l_per_min_per_pct * std::min(duty_pct, 100.0) + line.intercept_l_per_min) *
         pressure_scale(pressure_mpa, line.calibration_pressure_mpa);
}

double line_slope_l_per_min_per_pct(const NozzleLine& line, double pressure_mpa) noexcept {
  return line.slope_l_per_min_per_pct * pressure_scale(pressure_mpa, line.calibration_pressure_mpa);
}

double held_open_flow_l_per_min(const NozzleLine& line, double pressure_mpa) noexcept {
  if (!(line.full_open_flow_l_per_min > 0.0))
    return flow_for_duty_l_per_min(line, 100.0, pressure_mpa);
  return line.full_open_flow_l_per_min *
         pressure_scale(pressure_mpa, line.calibration_pressure_mpa);
}

SprayDecision spray_decision(const SprayLawConfig& c, const NozzleLine& line, double density,
                             double speed_m_per_s, double pressure_mpa) noexcept {
  SprayDecision decision;
  decision.target_flow_l_per_min = target_flow_l_per_min(c, density, speed_m_per_s);
  if (decision.target_flow_l_per_min <= 0.0) return decision;
  decision.raw_duty_pct = raw_duty_for_flow_pct(line, decision.target_flow_l_per_min, pressure_mpa);
  decision.duty_pct =
      clamp_duty_for_flow_pct(c, decision.raw_duty_pct, decision.target_flow_l_per_min);
  return decision;
}

double application_rate_l_per_ha(double flow_l_per_min, double speed_m_per_s,
                                 double width_m) noexcept {
  if (!(speed_m_per_s > 0.0) || !(width_m > 0.0) || !std::isfinite(flow_l_per_min)) return 0.0;
  // L/min -> L/s is /60; m^2/s -> ha/s is /10000.
  return flow_l_per_min * 10000.0 / (60.0 * speed_m_per_s * width_m);
}

DutyQuantiser::DutyQuantiser(std::span<const double> levels_pct, double hysteresis_pct)
    : count_(levels_pct.size()), hysteresis_pct_(hysteresis_pct) {
  require(count_ >= 1 && count_ <= kMaxLevels,
          "duty quantiser: need 1..16 levels, got " + std::to_string(count_));
  require(std::isfinite(hysteresis_pct) && hysteresis_pct >= 0.0,
          "duty quantiser: hysteresis_pct must be >= 0");
  for (std::size_t i = 0; i < count_; ++i) {
    const double level = levels_pct[i];
    require(std::isfinite(level) && level >= 0.0 && level <= 100.0,
            "duty quantiser: level " + std::to_string(i) + " outside [0, 100]");
    require(i == 0 || level > levels_pct[i - 1],
            "duty quantiser: levels must be strictly ascending (level " + std::to_string(i) + ")");
    levels_[i] = level;
  }
}

double DutyQuantiser::quantise(double duty_pct) noexcept {
  if (!std::isfinite(duty_pct)) duty_pct = 0.0;
  if (has_level_) {
    // Band of the current level: half-way to each neighbour, widened by the hysteresis.
    const double lower = current_ == 0
                             ? -1e300
                             : 0.5 * (levels_[current_ - 1] + levels_[current_]) - hysteresis_pct_;
    const double upper = current_ + 1 == count_
                             ? 1e300
                             : 0.5 * (levels_[current_] + levels_[current_ + 1]) + hysteresis_pct_;
    if (duty_pct >= lower && duty_pct <= upper) return levels_[current_];
  }
  std::size_t best = 0;
  for (std::size_t i = 1; i < count_; ++i) {
    if (std::abs(levels_[i] - duty_pct) < std::abs(levels_[best] - duty_pct)) best = i;
  }
  current_ = best;
  has_level_ = true;
  return levels_[current_];
}

}  // namespace weedspray::control
