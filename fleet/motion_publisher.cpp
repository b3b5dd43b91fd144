// SPDX-License-Identifier: Apache-2.0
#include "fleet/motion_publisher.hpp"

#include <cstdio>

#include "fleet/motion.hpp"

namespace weedspray::fleet {
namespace {

// sd-event's default timer accuracy (250 ms) would bunch the samples: 1 us asks for none.
constexpr std::uint64_t kTimerAccuracyUs = 1;

}  // namespace

MotionPublisher::MotionPublisher(sd_event* event, double rate_hz, DaemonClient& daemon,
                                 MqttLink& mqtt, const Topics& topics)
    : daemon_(daemon),
      mqtt_(mqtt),
      topic_(topics.board("motion")),
      timer_(
          event, rate_hz > 0 ? 1.0 / rate_hz : 0.0, kTimerAccuracyUs, [this] { take(); },
          "motion") {}

void MotionPublisher::take() {
  if (!daemon_.present() || pending_) return;
  pending_ = true;
  daemon_.motion([this](const MotionSample& sample, const std::string& error) {
    pending_ = false;
    if (!error.empty()) {
      if (failures_++ % 200 == 0) {
        std::fprintf(stderr, "motion not published (%llu so far): %s\n",
                     static_cast<unsigned long long>(failures_), error.c_str());
      }
      return;
    }
    mqtt_.publish(topic_, motion_payload(sample).dump(), false, 0);
  });
}

}  // namespace weedspray::fleet
