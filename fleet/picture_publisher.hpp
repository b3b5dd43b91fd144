// SPDX-License-Identifier: Apache-2.0
// The board's live-view picture on the broker: every interval, camera 0's latest frame with the
// weed overlay (the daemon's Snapshot, a PNG) published retained on weedspray/<m>/<b>/picture.
// Asynchronous on the main sd-event loop: a Snapshot still on its way skips the round, so a slow
// reply never holds up the status topics. Main thread only.
#pragma once

#include <cstdint>
#include <string>

#include <systemd/sd-event.h>

#include "fleet/daemon_client.hpp"
#include "fleet/mqtt_link.hpp"
#include "fleet/repeating_timer.hpp"
#include "fleet/topics.hpp"

namespace weedspray::fleet {

class PicturePublisher {
 public:
  // interval_s <= 0: never. Throws std::runtime_error when the timer cannot be made.
  PicturePublisher(sd_event* event, double interval_s, DaemonClient& daemon, MqttLink& mqtt,
                   const Topics& topics);
  PicturePublisher(const PicturePublisher&) = delete;
  PicturePublisher& operator=(const PicturePublisher&) = delete;

 private:
  void take();
  void done(const std::string& png, const std::string& error);

  DaemonClient& daemon_;
  MqttLink& mqtt_;
  std::string topic_;
  bool pending_ = false;
  std::uint64_t published_ = 0;
  std::uint64_t skipped_ = 0;  // RateLimited, Unavailable, a reply still pending, a bus error
  RepeatingTimer timer_;       // last: gone before what its callback uses
};

}  // namespace weedspray::fleet
