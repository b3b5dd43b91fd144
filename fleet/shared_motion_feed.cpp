// SPDX-License-Identifier: Apache-2.0
#include "fleet/shared_motion_feed.hpp"

#include <cstdio>

#include "fleet/motion.hpp"

namespace weedspray::fleet {

bool SharedMotionFeed::take(const MqttEvent& message) {
  if (topic_.empty() || message.topic != topic_) return false;
  // A retained sample is an old one replayed by the broker: never a speed of now.
  const auto sample = message.retained ? std::nullopt : parse_motion(message.payload);
  if (!sample) {
    outcome(false, message.retained ? "a retained sample" : "a malformed sample");
    return true;
  }
  if (!daemon_.present()) return true;
  daemon_.feed_motion(*sample, [this](Refusal refusal, const std::string& error) {
    outcome(refusal == Refusal::kNone, error);
  });
  return true;
}

void SharedMotionFeed::outcome(bool ok, const std::string& why) {
  if (ok) {
    if (failing_ || fed_ == 0) std::fprintf(stderr, "shared speed: fed from %s\n", topic_.c_str());
    ++fed_;
    failing_ = false;
    return;
  }
  ++dropped_;
  if (!failing_) {
    std::fprintf(stderr, "shared speed: sample dropped (%llu so far): %s\n",
                 static_cast<unsigned long long>(dropped_), why.c_str());
  }
  failing_ = true;
}

}  // namespace weedspray::fleet
