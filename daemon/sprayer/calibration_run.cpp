// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/calibration_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <span>
#include <stdexcept>
#include <utility>

namespace weedspray::daemon {

const char* to_string(CalibrationState state) noexcept {
  switch (state) {
    case CalibrationState::kCatchTest:
      return "catch_test";
    case CalibrationState::kAwaitingVolume:
      return "awaiting_volume";
    case CalibrationState::kNozzles:
      return "nozzles";
    case CalibrationState::kValveTest:
      return "valve_test";
    case CalibrationState::kPumpTest:
      return "pump_test";
    case CalibrationState::kDone:
      return "done";
    case CalibrationState::kCancelled:
      return "cancelled";
    case CalibrationState::kIdle:
      break;
  }
  return "idle";
}

CalibrationRun::CalibrationRun(std::size_t nozzles) : nozzles_(std::min(nozzles, io::kMaxValves)) {}

std::string CalibrationRun::start_catch_test(double duration_s, double now_s,
                                             std::uint64_t pulses) {
  if (running()) return std::string("a calibration is running (") + to_string(state_) + ")";
  if (!(duration_s >= 1.0 && duration_s <= 600.0)) return "the catch test must last 1..600 s";
  state_ = CalibrationState::kCatchTest;
  started_s_ = now_s;
  duration_s_ = duration_s;
  start_pulses_ = pulses;
  catch_pulses_ = 0;
  progress_ = 0.0;
  duties_.fill(0.0);
  std::fill_n(duties_.begin(), nozzles_, 100.0);
  message_ = "catch test: every nozzle open, collect the liquid";
  return {};
}

std::string CalibrationRun::start_nozzle_sweep(const NozzleSweepPlan& plan, double now_s,
                                               std::uint64_t pulses) {
  if (running()) return std::string("a calibration is running (") + to_string(state_) + ")";
  if (plan.duties_pct.size() < 2) return "the sweep needs at least 2 duties";
  if (!(plan.settle_s >= 0 && plan.measure_s > 0 && plan.pulses_per_litre > 0 &&
        plan.pressure_mpa > 0)) {
    return "the sweep needs settle_s >= 0, measure_s > 0, a meter K and a pressure";
  }
  plan_ = plan;
  state_ = CalibrationState::kNozzles;
  nozzle_ = 0;
  point_ = 0;
  points_.clear();
  fits_.assign(nozzles_, std::nullopt);
  progress_ = 0.0;
  measuring_ = false;
  phase_start_s_ = now_s + kPumpLeadInS;  // the first settle lasts the lead-in longer
  phase_pulses_ = pulses;
  set_point_duty();
  return {};
}

std::optional<control::FlowMeterCalibration> CalibrationRun::enter_volume(
    double volume_l, double configured_pulses_per_litre, double max_change_pct,
    std::string& error) {
  if (state_ != CalibrationState::kAwaitingVolume) {
    error = std::string("no catch test awaits its volume (calibration ") + to_string(state_) +
            "): run `sprayctl calibrate meter --seconds S` first";
    return std::nullopt;
  }
  if (!(volume_l > 0.0 && volume_l < 1000.0)) {
    error = "the collected volume must be > 0 and < 1000 L";
    return std::nullopt;
  }
  if (catch_pulses_ == 0) {
    error = "the meter counted no pulses during the catch test: is it wired?";
    return std::nullopt;
  }
  const control::FlowMeterCalibration result =
      control::calibrate_flow_meter(catch_pulses_, volume_l, configured_pulses_per_litre);
  const double change_pct =
      std::abs(result.pulses_per_litre / configured_pulses_per_litre - 1.0) * 100.0;
  if (change_pct > max_change_pct) {
    char text[320];
    std::snprintf(text, sizeof text,
                  "%.3f L over %llu pulses is %.1f pulses/L, %.0f %% off the configured %.1f "
                  "(at most calibration.meter_max_change_pct = %.0f %%): was the volume typed "
                  "right? If the meter truly differs that much, set flow.pulses_per_litre",
                  volume_l, static_cast<unsigned long long>(catch_pulses_), result.pulses_per_litre,
                  change_pct, configured_pulses_per_litre, max_change_pct);
    error = text;
    return std::nullopt;
  }
  state_ = CalibrationState::kDone;
  progress_ = 1.0;
  char text[160];
  std::snprintf(text, sizeof text, "meter: %.1f pulses/L (configured %.1f, its error %+.2f %%)",
                result.pulses_per_litre, result.configured_pulses_per_litre, result.error_pct);
  message_ = text;
  return result;
}

void CalibrationRun::cancel(std::string_view why) {
  if (!running() && state_ != CalibrationState::kAwaitingVolume) return;
  message_ = std::string(to_string(state_)) + " cancelled: " + std::string(why);
  state_ = CalibrationState::kCancelled;
  duties_.fill(0.0);
  fits_.clear();
}

void CalibrationRun::update(double now_s, std::uint64_t pulses) {
  if (state_ == CalibrationState::kValveTest || state_ == CalibrationState::kPumpTest) {
    update_output_test(now_s, pulses);
    return;
  }
  if (state_ == CalibrationState::kCatchTest) {
    const double elapsed = now_s - started_s_;
    progress_ = std::clamp(elapsed / (duration_s_ + kDrainS), 0.0, 0.999);
    if (elapsed >= duration_s_) duties_.fill(0.0);
    if (elapsed < duration_s_ + kDrainS) return;
    catch_pulses_ = pulses - start_pulses_;
    state_ = CalibrationState::kAwaitingVolume;
    message_ = "catch test done: " + std::to_string(catch_pulses_) +
               " pulses; enter the collected volume (sprayctl calibrate meter --volume L)";
    return;
  }
  if (state_ != CalibrationState::kNozzles) return;
  const double points = static_cast<double>(points_per_nozzle());
  const double steps = points * static_cast<double>(nozzles_);
  const double step_s = plan_.settle_s + plan_.measure_s;
  const double in_step =
      std::clamp((now_s - phase_start_s_ + (measuring_ ? plan_.settle_s : 0)) / step_s, 0.0, 1.0);
  progress_ = std::min(
      0.999,
      (static_cast<double>(nozzle_) * points + static_cast<double>(point_) + in_step) / steps);
  if (!measuring_) {
    if (now_s - phase_start_s_ < plan_.settle_s) return;
    measuring_ = true;
    phase_start_s_ = now_s;
    phase_pulses_ = pulses;
    return;
  }
  const double measured_s = now_s - phase_start_s_;
  if (measured_s < plan_.measure_s) return;
  // The window's true length (the main loop's ticks are not exact): flow over what was counted.
  const double litres = static_cast<double>(pulses - phase_pulses_) / plan_.pulses_per_litre;
  points_.push_back({point_duty_pct(point_), litres / (measured_s / 60.0)});
  measuring_ = false;
  phase_start_s_ = now_s;
  if (++point_ < points_per_nozzle()) {
    set_point_duty();
    return;
  }
  finish_nozzle();
}

std::size_t CalibrationRun::points_per_nozzle() const noexcept {
  return plan_.duties_pct.size() + (plan_.full_open ? 1 : 0);
}

// The plan's duties, then (full_open) 100 %: held open.
double CalibrationRun::point_duty_pct(std::size_t point) const noexcept {
  return point < plan_.duties_pct.size() ? plan_.duties_pct[point] : 100.0;
}

void CalibrationRun::set_point_duty() {
  duties_.fill(0.0);
  duties_[nozzle_] = point_duty_pct(point_);
  char text[120];
  std::snprintf(text, sizeof text, "nozzle %zu of %zu at %.0f %% duty%s", nozzle_ + 1, nozzles_,
                point_duty_pct(point_), point_ < plan_.duties_pct.size() ? "" : " (held open)");
  message_ = text;
}

void CalibrationRun::finish_nozzle() {
  const auto [lo, hi] = std::minmax_element(plan_.duties_pct.begin(), plan_.duties_pct.end());
  // The held-open point lies outside [lo, hi]: fit_nozzle_line leaves it out of the line.
  const std::span<const control::DutyFlowPoint> swept(points_.data(), plan_.duties_pct.size());
  try {
    fits_[nozzle_] = control::fit_nozzle_line(swept, plan_.pressure_mpa, *lo, *hi);
  } catch (const std::invalid_argument&) {
    fits_[nozzle_] = std::nullopt;  // reported as "no line" below; the configured line stays
  }
  // Held open, a nozzle passes at least what its line says at the highest swept duty; less is
  // a meter or valve problem, not a full-open flow to hold the valve open at (left unknown).
  if (fits_[nozzle_] && plan_.full_open && points_.size() > plan_.duties_pct.size()) {
    const double held_open = points_.back().flow_l_per_min;
    const control::NozzleLine& line = fits_[nozzle_]->line;
    if (held_open >= line.slope_l_per_min_per_pct * *hi + line.intercept_l_per_min)
      fits_[nozzle_]->line.full_open_flow_l_per_min = held_open;
  }
  points_.clear();
  point_ = 0;
  if (++nozzle_ < nozzles_) {
    set_point_duty();
    return;
  }
  duties_.fill(0.0);
  state_ = CalibrationState::kDone;
  progress_ = 1.0;
  double lowest_r2 = 1.0;
  std::size_t fitted = 0;
  std::size_t held_open = 0;
  for (const auto& fit : fits_) {
    if (!fit) continue;
    ++fitted;
    lowest_r2 = std::min(lowest_r2, fit->r_squared);
    if (fit->line.full_open_flow_l_per_min > 0) ++held_open;
  }
  char text[200];
  std::snprintf(text, sizeof text, "nozzles: %zu of %zu lines fitted, lowest R^2 %.4f", fitted,
                nozzles_, lowest_r2);
  if (plan_.full_open) {
    const std::size_t n = std::strlen(text);
    std::snprintf(text + n, sizeof text - n, ", %zu full-open flows", held_open);
  }
  message_ = text;
}

std::vector<std::optional<control::NozzleLineFit>> CalibrationRun::take_fits() {
  return std::exchange(fits_, {});
}

}  // namespace weedspray::daemon
