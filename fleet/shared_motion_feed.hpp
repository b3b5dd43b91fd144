// SPDX-License-Identifier: Apache-2.0
// The board that takes its speed from another (fleet.speed_from): each sample on that board's
// motion topic handed to this board's daemon (FeedSharedMotion), which stamps it with its own
// clock. Nothing is kept or repeated here: when samples stop coming (that board, the broker or
// this link gone) the daemon's own timeout closes the valves. Main thread only.
#pragma once

#include <cstdint>
#include <string>

#include "fleet/daemon_client.hpp"
#include "fleet/mqtt_link.hpp"

namespace weedspray::fleet {

class SharedMotionFeed {
 public:
  SharedMotionFeed(DaemonClient& daemon, std::string topic)
      : daemon_(daemon), topic_(std::move(topic)) {}

  // The topic subscribed to ("" when fleet.speed_from is empty).
  [[nodiscard]] const std::string& topic() const { return topic_; }
  // True when the message was the motion topic's (taken or dropped), false otherwise.
  bool take(const MqttEvent& message);

 private:
  // Logs the first refusal and the recovery, not 20 lines a second.
  void outcome(bool ok, const std::string& why);

  DaemonClient& daemon_;
  std::string topic_;
  std::uint64_t fed_ = 0;
  std::uint64_t dropped_ = 0;
  bool failing_ = false;
};

}  // namespace weedspray::fleet
