// SPDX-License-Identifier: Apache-2.0
// The board that owns the speed (fleet.motion_rate_hz > 0): at that rate, the daemon's latest
// ground speed and odometer with its clock (Motion) published on weedspray/<m>/<b>/motion, QoS 0
// and not retained: a late sample is worth nothing and a stale one must never be replayed.
// Asynchronous on the main sd-event loop: a Motion call still on its way skips the round.
#pragma once

#include <cstdint>
#include <string>

#include <systemd/sd-event.h>

#include "fleet/daemon_client.hpp"
#include "fleet/mqtt_link.hpp"
#include "fleet/repeating_timer.hpp"
#include "fleet/topics.hpp"

namespace weedspray::fleet {

class MotionPublisher {
 public:
  // rate_hz <= 0: never. Throws std::runtime_error when the timer cannot be made.
  MotionPublisher(sd_event* event, double rate_hz, DaemonClient& daemon, MqttLink& mqtt,
                  const Topics& topics);
  MotionPublisher(const MotionPublisher&) = delete;
  MotionPublisher& operator=(const MotionPublisher&) = delete;

 private:
  void take();

  DaemonClient& daemon_;
  MqttLink& mqtt_;
  std::string topic_;
  bool pending_ = false;
  std::uint64_t failures_ = 0;
  RepeatingTimer timer_;  // last: gone before what its callback uses
};

}  // namespace weedspray::fleet
