// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/shared_position.hpp"

namespace weedspray::daemon {

GnssSample shared_gnss_sample(const SharedMotionSample& latest,
                              const SharedMotionTracker& tracker) noexcept {
  GnssSample sample;
  if (!latest.fix.has_position()) {
    sample.sample_time = latest.arrival;
    return sample;  // mode none
  }
  sample.value.latitude_deg = latest.fix.latitude_deg;
  sample.value.longitude_deg = latest.fix.longitude_deg;
  sample.value.course_deg = latest.fix.heading_deg;
  sample.value.speed_m_per_s = tracker.speed_m_per_s();
  sample.value.mode = latest.fix.mode;
  sample.value.utc_ns = latest.fix.utc_ns;
  sample.sample_time = tracker.local_time(latest.fix.sender_time_ns);
  return sample;
}

}  // namespace weedspray::daemon
