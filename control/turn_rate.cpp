// SPDX-License-Identifier: Apache-2.0
#include "control/turn_rate.hpp"

#include <cmath>
#include <numbers>

namespace weedspray::control {

double course_difference_deg(double from_deg, double to_deg) noexcept {
  double d = std::fmod(to_deg - from_deg, 360.0);
  if (d > 180.0) d -= 360.0;
  if (d <= -180.0) d += 360.0;
  return d;
}

void YawRateEstimator::reset() noexcept {
  have_previous_ = false;
  rate_deg_per_s_ = 0;
}

double YawRateEstimator::add_fix(double course_deg, double speed_m_per_s, double time_s) noexcept {
  if (!std::isfinite(course_deg) || !std::isfinite(speed_m_per_s) || !std::isfinite(time_s) ||
      speed_m_per_s < config_.min_speed_m_per_s) {
    reset();
    return rate_deg_per_s_;
  }
  if (have_previous_) {
    const double dt = time_s - previous_time_s_;
    if (dt <= 0.0) return rate_deg_per_s_;  // the same fix again (or time went back): no news
    if (dt > config_.max_fix_gap_s) {
      rate_deg_per_s_ = 0;  // too old to difference: start a new chain from this fix
    } else {
      const double raw = course_difference_deg(previous_course_deg_, course_deg) / dt;
      // Exact discretisation of a first-order low-pass over a step of dt.
      const double tau = config_.filter_time_constant_s;
      const double alpha = tau > 0.0 ? 1.0 - std::exp(-dt / tau) : 1.0;
      rate_deg_per_s_ += alpha * (raw - rate_deg_per_s_);
    }
  }
  have_previous_ = true;
  previous_course_deg_ = course_deg;
  previous_time_s_ = time_s;
  return rate_deg_per_s_;
}

double nozzle_ground_speed_m_per_s(double speed_m_per_s, double yaw_rate_deg_per_s,
                                   double right_offset_m) noexcept {
  const double w = yaw_rate_deg_per_s * std::numbers::pi / 180.0;
  const double v = speed_m_per_s - w * right_offset_m;
  return v > 0.0 ? v : 0.0;
}

}  // namespace weedspray::control
