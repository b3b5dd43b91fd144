// SPDX-License-Identifier: Apache-2.0
// Turn compensation: on a curve each nozzle moves over the ground at its own speed.
// A rigid boom turning at yaw rate w (rad/s, CLOCKWISE positive seen from above, as a course
// over ground grows) about a centre on the curve's inside: a nozzle y metres RIGHT of the
// machine's centre line moves at
//     v_i = v - w y          (right turn: the right nozzles are the inner, slower ones)
// which is the v + yaw_rate x lateral offset with the offset taken to the left. Below
// zero (a turn tighter than the nozzle's offset) the nozzle moves backwards over ground it has
// sprayed: its speed is taken as 0 (closed).
//
// The yaw rate comes from the receiver's course over ground: successive fixes' course change
// (wrapped to +-180 deg) over their time difference, low-passed. Below a minimum speed the
// course is noise (a standing receiver's course wanders), so the rate is 0 and the history is
// reset. Pure: the caller gives each fix's course, speed and time.
#pragma once

#include <cstdint>

namespace weedspray::control {

struct YawRateConfig {
  double min_speed_m_per_s = 0.3;       // below: yaw rate 0 (course is noise)
  double filter_time_constant_s = 0.5;  // first-order low-pass; 0 = none
  double max_fix_gap_s = 2.0;           // two fixes further apart than this do not make a rate
};

class YawRateEstimator {
 public:
  explicit YawRateEstimator(const YawRateConfig& config) noexcept : config_(config) {}
  // One GNSS fix: course (deg from north, clockwise), speed over ground, its time (s, any
  // monotonic origin: the receiver's UTC when known). Non-finite course or speed: the fix gives
  // no rate (and breaks the difference chain). Returns the filtered rate, deg/s clockwise.
  double add_fix(double course_deg, double speed_m_per_s, double time_s) noexcept;
  // Forget the history (fix lost): the rate is 0 until two fixes make a new one.
  void reset() noexcept;
  double rate_deg_per_s() const noexcept { return rate_deg_per_s_; }

 private:
  YawRateConfig config_;
  bool have_previous_ = false;
  double previous_course_deg_ = 0;
  double previous_time_s_ = 0;
  double rate_deg_per_s_ = 0;
};

// Course change from `from_deg` to `to_deg`, wrapped to (-180, 180].
double course_difference_deg(double from_deg, double to_deg) noexcept;

// A nozzle's ground speed on a turn: v - w y, w in deg/s clockwise, y metres right of the
// centre line; never below 0.
double nozzle_ground_speed_m_per_s(double speed_m_per_s, double yaw_rate_deg_per_s,
                                   double right_offset_m) noexcept;

}  // namespace weedspray::control
