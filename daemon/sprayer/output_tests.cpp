// SPDX-License-Identifier: Apache-2.0
// Commissioning checks of the outputs (sprayctl test valve / pump): CalibrationRun's valve and
// pump tests. A machine builder runs them once wired, before the first calibration: does this
// valve open and the meter count, does the pump build the set-point pressure.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "daemon/sprayer/calibration_run.hpp"

namespace weedspray::daemon {

namespace {
// The pump test counts the set-point reached once the pressure is within this share of it.
constexpr double kReachedShare = 0.95;
}  // namespace

std::string CalibrationRun::start_valve_test(std::size_t nozzle, double duty_pct, double duration_s,
                                             double now_s, std::uint64_t pulses,
                                             double pulses_per_litre) {
  if (running()) return std::string("a calibration is running (") + to_string(state_) + ")";
  if (nozzle >= nozzles_)
    return "nozzle " + std::to_string(nozzle) + " does not exist (nozzles 0.." +
           std::to_string(nozzles_ - 1) + ")";
  if (!(duty_pct > 0.0 && duty_pct <= 100.0)) return "the duty must be > 0 and <= 100 %";
  if (!(duration_s >= 1.0 && duration_s <= 60.0)) return "a valve test lasts 1..60 s";
  state_ = CalibrationState::kValveTest;
  started_s_ = now_s;
  duration_s_ = duration_s;
  start_pulses_ = pulses;
  tested_nozzle_ = nozzle;
  tested_duty_pct_ = duty_pct;
  test_pulses_per_litre_ = pulses_per_litre;
  progress_ = 0.0;
  duties_.fill(0.0);
  duties_[nozzle] = duty_pct;
  char text[120];
  std::snprintf(text, sizeof text,
                "valve test: nozzle %zu at %.0f %% for %.0f s, the others closed", nozzle, duty_pct,
                duration_s);
  message_ = text;
  return {};
}

std::string CalibrationRun::start_pump_test(double duration_s, double now_s, double setpoint_mpa) {
  if (running()) return std::string("a calibration is running (") + to_string(state_) + ")";
  if (!(duration_s >= 1.0 && duration_s <= 120.0)) return "a pump test lasts 1..120 s";
  if (!(setpoint_mpa > 0.0)) return "the pressure set-point must be > 0";
  state_ = CalibrationState::kPumpTest;
  started_s_ = now_s;
  duration_s_ = duration_s;
  test_setpoint_mpa_ = setpoint_mpa;
  peak_pressure_mpa_ = 0.0;
  reached_after_s_ = -1.0;
  progress_ = 0.0;
  duties_.fill(0.0);
  char text[120];
  std::snprintf(text, sizeof text,
                "pump test: pump on holding %.3f MPa for %.0f s, every valve closed", setpoint_mpa,
                duration_s);
  message_ = text;
  return {};
}

void CalibrationRun::observe_pressure(double now_s, double pressure_mpa) noexcept {
  if (state_ != CalibrationState::kPumpTest || !std::isfinite(pressure_mpa)) return;
  peak_pressure_mpa_ = std::max(peak_pressure_mpa_, pressure_mpa);
  if (reached_after_s_ < 0 && pressure_mpa >= kReachedShare * test_setpoint_mpa_)
    reached_after_s_ = now_s - started_s_;
}

void CalibrationRun::update_output_test(double now_s, std::uint64_t pulses) {
  const double elapsed = now_s - started_s_;
  progress_ = std::clamp(elapsed / duration_s_, 0.0, 0.999);
  if (elapsed < duration_s_) return;
  duties_.fill(0.0);
  progress_ = 1.0;
  if (state_ == CalibrationState::kValveTest)
    finish_valve_test(pulses);
  else
    finish_pump_test();
  state_ = CalibrationState::kDone;
}

void CalibrationRun::finish_valve_test(std::uint64_t pulses) {
  const std::uint64_t counted = pulses - start_pulses_;
  char text[240];
  if (test_pulses_per_litre_ <= 0.0) {
    std::snprintf(text, sizeof text,
                  "valve test: nozzle %zu at %.0f %% for %.0f s done (no flow meter: judge the "
                  "spray by eye)",
                  tested_nozzle_, tested_duty_pct_, duration_s_);
  } else if (counted == 0) {
    std::snprintf(text, sizeof text,
                  "valve test: nozzle %zu at %.0f %% for %.0f s: the meter counted NO pulses: "
                  "check the valve's line and relay, the nozzle, and the meter's wiring",
                  tested_nozzle_, tested_duty_pct_, duration_s_);
  } else {
    const double litres = static_cast<double>(counted) / test_pulses_per_litre_;
    std::snprintf(text, sizeof text,
                  "valve test: nozzle %zu at %.0f %% for %.0f s: %llu pulses, %.3f L, %.3f L/min "
                  "by the meter",
                  tested_nozzle_, tested_duty_pct_, duration_s_,
                  static_cast<unsigned long long>(counted), litres, litres / (duration_s_ / 60.0));
  }
  message_ = text;
}

void CalibrationRun::finish_pump_test() {
  char text[260];
  if (reached_after_s_ >= 0) {
    std::snprintf(text, sizeof text,
                  "pump test: %.3f MPa reached after %.1f s (peak %.3f MPa) with every valve "
                  "closed",
                  test_setpoint_mpa_, reached_after_s_, peak_pressure_mpa_);
  } else {
    std::snprintf(text, sizeof text,
                  "pump test: the set-point %.3f MPa was NOT reached in %.0f s (highest %.3f "
                  "MPa): check the pump relay, the return valve's DAC and the pressure sensor "
                  "(sprayctl inputs)",
                  test_setpoint_mpa_, duration_s_, peak_pressure_mpa_);
  }
  message_ = text;
}

}  // namespace weedspray::daemon
