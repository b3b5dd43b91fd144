// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/shared_motion.hpp"

#include <algorithm>
#include <cmath>

namespace weedspray::daemon {
namespace {

double seconds(std::chrono::nanoseconds t) {
  return std::chrono::duration<double>(t).count();
}

}  // namespace

void SharedMotionTracker::update(const SharedMotionSample& latest,
                                 std::chrono::nanoseconds now) noexcept {
  took_sample_ = false;
  const bool usable = std::isfinite(latest.speed_m_per_s) && std::isfinite(latest.distance_m);
  // A new sample, not one overtaken by a later one already taken. After a loss anything goes:
  // the owning board may have restarted, its clock and odometer with it.
  if (latest.count != seen_count_ && usable &&
      (!fresh_ || latest.sender_time_ns > last_sender_time_ns_)) {
    const double arrival_s = seconds(latest.arrival);
    const double offset_s = arrival_s - static_cast<double>(latest.sender_time_ns) * 1e-9;
    if (!fresh_) {
      offset_s_ = offset_s;
    } else {
      offset_s_ = std::min(offset_s_ + kOffsetRise * (arrival_s - last_arrival_s_), offset_s);
    }
    extra_age_s_ = offset_s - offset_s_;
    last_arrival_s_ = arrival_s;
    last_sender_time_ns_ = latest.sender_time_ns;
    sample_distance_m_ = latest.distance_m;
    speed_m_per_s_ = latest.speed_m_per_s;
    sample_arrival_ = latest.arrival;
    if (!fresh_) distance_m_ = latest.distance_m;  // the first, or back after a loss
    fresh_ = true;
    had_sample_ = true;
    took_sample_ = true;
  }
  seen_count_ = latest.count;
  if (fresh_ && now - sample_arrival_ > timeout_) fresh_ = false;
  if (!fresh_) return;
  const double carried_s = extra_age_s_ + seconds(now - sample_arrival_);
  distance_m_ = std::max(distance_m_, sample_distance_m_ + speed_m_per_s_ * carried_s);
}

std::chrono::nanoseconds SharedMotionTracker::local_time(
    std::uint64_t sender_time_ns) const noexcept {
  const double local_s = static_cast<double>(sender_time_ns) * 1e-9 + offset_s_;
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double>(local_s));
}

}  // namespace weedspray::daemon
