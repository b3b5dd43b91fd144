// SPDX-License-Identifier: Apache-2.0
// Wheel-sensor calibration from GNSS over a straight run: drive straight at a
// steady speed; the receiver measures the distance, the wheel sensor counts its pulses, and
// pulses / distance is the wheel's pulses_per_metre as it rolls on this soil (slip included).
// The distance is the straight line between the run's first and last fixes: on a straight run
// it is the path, and its error is the two end fixes' position errors alone (about 2 x 1.5 m
// for an autonomous receiver, 2 x 2 cm with RTK), so a run of 100 m gives 1-3 % or better
// than 0.1 %. A run that is not straight (the course over ground, from Doppler and smooth
// where positions are not, off its start by more than the tolerance) starts again from that
// fix; so does a fix that is not usable or slower than the minimum speed. Pure: the caller gives
// each fix with the wheel's pulse count when the fix arrived.
#pragma once

#include <cstdint>
#include <string_view>

namespace weedspray::control {

struct WheelCalibrationConfig {
  double run_distance_m = 100.0;       // straight-line distance that completes the calibration
  double max_course_change_deg = 3.0;  // from the run's first fix
  double min_speed_m_per_s = 0.5;      // slower: the course is noise, the run starts again
};

enum class WheelCalibrationState : std::uint8_t { kIdle, kWaitingForRun, kRunning, kDone };
// "idle", "waiting" (for a straight run at speed), "running", "done"
std::string_view to_string(WheelCalibrationState state) noexcept;

struct WheelCalibrationStatus {
  WheelCalibrationState state = WheelCalibrationState::kIdle;
  double distance_m = 0;        // of the current run (kRunning, kDone)
  std::uint64_t pulses = 0;     // of the current run
  double pulses_per_metre = 0;  // kDone
  std::uint32_t restarts = 0;   // runs broken by a turn, a stop or a lost fix
};

struct CalibrationFix {
  bool usable = false;  // a 2D/3D fix, fresh
  double latitude_deg = 0;
  double longitude_deg = 0;
  double course_deg = 0;
  double speed_m_per_s = 0;
};

class WheelCalibration {
 public:
  explicit WheelCalibration(const WheelCalibrationConfig& config) noexcept : config_(config) {}
  // Begins a calibration (forgets any earlier result).
  void start() noexcept;
  // One fix and the wheel counter's reading when it arrived (free-running, wraps at 2^64).
  const WheelCalibrationStatus& add_fix(const CalibrationFix& fix,
                                        std::uint64_t wheel_count) noexcept;
  const WheelCalibrationStatus& status() const noexcept { return status_; }

 private:
  void begin_run(const CalibrationFix& fix, std::uint64_t wheel_count) noexcept;

  WheelCalibrationConfig config_;
  WheelCalibrationStatus status_;
  CalibrationFix start_{};
  std::uint64_t start_count_ = 0;
};

// Ground distance between two nearby WGS84 points, metres: the WGS84 ellipsoid's meridian and
// prime-vertical radii at their mean latitude (a sphere's mean radius would be off by up to
// 0.5 % depending on latitude and direction, a bias the calibration would keep). For runs up to
// a few km the flat-Earth step is far below GNSS error.
double ground_distance_m(double lat1_deg, double lon1_deg, double lat2_deg,
                         double lon2_deg) noexcept;

}  // namespace weedspray::control
