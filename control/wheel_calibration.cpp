// SPDX-License-Identifier: Apache-2.0
#include "control/wheel_calibration.hpp"

#include <cmath>
#include <numbers>

#include "control/turn_rate.hpp"

namespace weedspray::control {

double ground_distance_m(double lat1_deg, double lon1_deg, double lat2_deg,
                         double lon2_deg) noexcept {
  constexpr double kA = 6378137.0;          // WGS84 semi-major axis
  constexpr double kE2 = 6.69437999014e-3;  // first eccentricity squared
  constexpr double kRad = std::numbers::pi / 180.0;
  const double phi = 0.5 * (lat1_deg + lat2_deg) * kRad;
  const double w = 1.0 - kE2 * std::sin(phi) * std::sin(phi);
  const double meridian = kA * (1.0 - kE2) / (w * std::sqrt(w));
  const double prime_vertical = kA / std::sqrt(w);
  const double north = (lat2_deg - lat1_deg) * kRad * meridian;
  const double east = (lon2_deg - lon1_deg) * kRad * prime_vertical * std::cos(phi);
  return std::hypot(north, east);
}

std::string_view to_string(WheelCalibrationState state) noexcept {
  switch (state) {
    case WheelCalibrationState::kIdle:
      return "idle";
    case WheelCalibrationState::kWaitingForRun:
      return "waiting";
    case WheelCalibrationState::kRunning:
      return "running";
    case WheelCalibrationState::kDone:
      return "done";
  }
  return "idle";
}

void WheelCalibration::start() noexcept {
  status_ = WheelCalibrationStatus{};
  status_.state = WheelCalibrationState::kWaitingForRun;
}

void WheelCalibration::begin_run(const CalibrationFix& fix, std::uint64_t wheel_count) noexcept {
  if (status_.state == WheelCalibrationState::kRunning) ++status_.restarts;
  status_.state = WheelCalibrationState::kRunning;
  status_.distance_m = 0;
  status_.pulses = 0;
  start_ = fix;
  start_count_ = wheel_count;
}

const WheelCalibrationStatus& WheelCalibration::add_fix(const CalibrationFix& fix,
                                                        std::uint64_t wheel_count) noexcept {
  if (status_.state == WheelCalibrationState::kIdle ||
      status_.state == WheelCalibrationState::kDone) {
    return status_;
  }
  const bool moving = fix.usable && std::isfinite(fix.latitude_deg) &&
                      std::isfinite(fix.longitude_deg) && std::isfinite(fix.course_deg) &&
                      fix.speed_m_per_s >= config_.min_speed_m_per_s;
  if (!moving) {
    if (status_.state == WheelCalibrationState::kRunning) ++status_.restarts;
    status_.state = WheelCalibrationState::kWaitingForRun;
    status_.distance_m = 0;
    status_.pulses = 0;
    return status_;
  }
  if (status_.state == WheelCalibrationState::kWaitingForRun) {
    begin_run(fix, wheel_count);
    return status_;
  }
  const double chord = ground_distance_m(start_.latitude_deg, start_.longitude_deg,
                                         fix.latitude_deg, fix.longitude_deg);
  const bool turned = std::abs(course_difference_deg(start_.course_deg, fix.course_deg)) >
                      config_.max_course_change_deg;
  if (turned) {
    begin_run(fix, wheel_count);
    return status_;
  }
  status_.distance_m = chord;
  status_.pulses = wheel_count - start_count_;  // unsigned: a wrapped counter still subtracts
  if (chord >= config_.run_distance_m) {
    status_.pulses_per_metre = static_cast<double>(status_.pulses) / chord;
    status_.state = WheelCalibrationState::kDone;
  }
  return status_;
}

}  // namespace weedspray::control
