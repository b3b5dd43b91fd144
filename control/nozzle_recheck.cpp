// SPDX-License-Identifier: Apache-2.0
#include "control/nozzle_recheck.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace weedspray::control {

void validate(const NozzleRecheckConfig& c) {
  auto require = [](bool ok, const char* field) {
    if (!ok) throw std::invalid_argument(std::string("NozzleRecheckConfig.") + field);
  };
  require(c.nozzles >= 1 && c.nozzles <= kMaxRecheckNozzles, "nozzles must be in [1, 32]");
  require(c.settle_s >= 0 && std::isfinite(c.settle_s), "settle_s must be >= 0 and finite");
  require(c.measure_s > 0 && std::isfinite(c.measure_s), "measure_s must be > 0 and finite");
  require(c.interval_s >= 0 && std::isfinite(c.interval_s), "interval_s must be >= 0 and finite");
  require(c.warn_fraction > 0 && c.warn_fraction < 1, "warn_fraction must be in (0, 1)");
  require(c.alarm_fraction >= c.warn_fraction && c.alarm_fraction < 1,
          "alarm_fraction must be in [warn_fraction, 1)");
  require(c.tolerance >= 0 && c.tolerance < c.warn_fraction,
          "tolerance must be in [0, warn_fraction)");
  require(c.min_scale > 0 && c.min_scale <= 1 && c.max_scale >= 1 && std::isfinite(c.max_scale),
          "min_scale must be in (0, 1] and max_scale >= 1");
}

NozzleLine scaled_line(const NozzleLine& line, double scale) noexcept {
  NozzleLine out = line;
  out.slope_l_per_min_per_pct *= scale;
  out.intercept_l_per_min *= scale;
  out.full_open_flow_l_per_min *= scale;
  return out;
}

NozzleRecheck::NozzleRecheck(const NozzleRecheckConfig& config) : config_(config) {
  validate(config_);
  reset();
}

void NozzleRecheck::reset() noexcept {
  duties_.fill(0.0);
  ratio_.fill(1.0);
  measured_at_s_.fill(-1.0);
  in_progress_ = false;
  ever_started_ = false;
  overriding_ = false;
  measuring_ = false;
  nozzle_ = 0;
  started_s_ = 0.0;
  has_last_ = false;
  phase_s_ = 0.0;
  phase_pulses_ = 0;
  promised_l_ = 0.0;
  warned_ = -1;
  alarmed_ = -1;
  completed_ = 0;
}

double NozzleRecheck::ratio(std::size_t nozzle) const noexcept {
  return nozzle < config_.nozzles ? ratio_[nozzle] : 1.0;
}

double NozzleRecheck::measured_at_s(std::size_t nozzle) const noexcept {
  return nozzle < config_.nozzles ? measured_at_s_[nozzle] : -1.0;
}

double NozzleRecheck::scale(std::size_t nozzle) const noexcept {
  return std::clamp(ratio(nozzle), config_.min_scale, config_.max_scale);
}

void NozzleRecheck::start_nozzle(const RecheckInput& in) noexcept {
  duties_.fill(0.0);
  duties_[nozzle_] = 100.0;
  overriding_ = true;
  measuring_ = false;
  phase_s_ = 0.0;
  phase_pulses_ = in.meter_pulses;
  promised_l_ = 0.0;
}

void NozzleRecheck::step(const RecheckInput& in, std::span<const NozzleLine> lines) noexcept {
  const double dt = has_last_ ? std::max(0.0, in.now_s - last_now_s_) : 0.0;
  has_last_ = true;
  last_now_s_ = in.now_s;
  if (!in.window) {
    // Crop again: release the valves now; the nozzle being read is read again next window.
    overriding_ = false;
    measuring_ = false;
    phase_s_ = 0.0;
    duties_.fill(0.0);
    return;
  }
  if (!in_progress_) {
    const bool due = !ever_started_ || in.now_s - started_s_ >= config_.interval_s;
    if (!due) return;
    in_progress_ = true;
    ever_started_ = true;
    started_s_ = in.now_s;
    nozzle_ = 0;
    start_nozzle(in);
    return;
  }
  if (!overriding_) {  // a window after one that closed mid-boom: resume at the same nozzle
    start_nozzle(in);
    return;
  }
  if (!in.pressure_ok) {
    // Not read at a pressure the loop has not caught: settle again once it has.
    measuring_ = false;
    phase_s_ = 0.0;
    return;
  }
  phase_s_ += dt;
  if (!measuring_) {
    if (phase_s_ < config_.settle_s) return;
    measuring_ = true;
    phase_s_ = 0.0;
    phase_pulses_ = in.meter_pulses;
    promised_l_ = 0.0;
    return;
  }
  if (nozzle_ < lines.size())
    promised_l_ += held_open_flow_l_per_min(lines[nozzle_], in.pressure_mpa) * dt / 60.0;
  if (phase_s_ + 1e-9 < config_.measure_s) return;
  finish_nozzle(in);
}

void NozzleRecheck::finish_nozzle(const RecheckInput& in) noexcept {
  // No reading without a meter K, a promise (line and pressure) or a count that went forward
  // (a meter reset): the nozzle keeps its last verdict.
  if (in.pulses_per_litre > 0.0 && promised_l_ > 0.0 && in.meter_pulses >= phase_pulses_) {
    const double metered_l =
        static_cast<double>(in.meter_pulses - phase_pulses_) / in.pulses_per_litre;
    ratio_[nozzle_] = metered_l / promised_l_;
    measured_at_s_[nozzle_] = in.now_s;
    judge();
  }
  if (++nozzle_ < config_.nozzles) {
    start_nozzle(in);
    return;
  }
  in_progress_ = false;
  overriding_ = false;
  measuring_ = false;
  nozzle_ = 0;
  duties_.fill(0.0);
  ++completed_;
}

void NozzleRecheck::judge() noexcept {
  const double warn_limit = config_.warn_fraction - config_.tolerance;
  const double alarm_limit = config_.alarm_fraction - config_.tolerance;
  double worst_warn = 0.0;
  double worst_alarm = 0.0;
  warned_ = -1;
  alarmed_ = -1;
  for (std::size_t i = 0; i < config_.nozzles; ++i) {
    const double off = std::abs(ratio_[i] - 1.0);
    if (off >= warn_limit && off > worst_warn) {
      worst_warn = off;
      warned_ = static_cast<int>(i);
    }
    if (off >= alarm_limit && off > worst_alarm) {
      worst_alarm = off;
      alarmed_ = static_cast<int>(i);
    }
  }
}

}  // namespace weedspray::control
