// SPDX-License-Identifier: Apache-2.0
#include "fleet/picture_publisher.hpp"

#include <cstdio>

namespace weedspray::fleet {

PicturePublisher::PicturePublisher(sd_event* event, double interval_s, DaemonClient& daemon,
                                   MqttLink& mqtt, const Topics& topics)
    : daemon_(daemon),
      mqtt_(mqtt),
      topic_(topics.board("picture")),
      timer_(
          event, interval_s, 0, [this] { take(); }, "picture") {}

void PicturePublisher::take() {
  if (!daemon_.present()) return;
  if (pending_) {
    ++skipped_;
    return;
  }
  pending_ = true;
  daemon_.picture(0, [this](std::string png, const std::string& error) { done(png, error); });
}

void PicturePublisher::done(const std::string& png, const std::string& error) {
  pending_ = false;
  if (!error.empty()) {
    // RateLimited (another client's Snapshot) or Unavailable (no frame yet): the next round.
    if (skipped_++ % 60 == 0) {
      std::fprintf(stderr, "picture skipped (%llu so far): %s\n",
                   static_cast<unsigned long long>(skipped_), error.c_str());
    }
    return;
  }
  mqtt_.publish(topic_, png, true);
  if (published_++ == 0) {
    std::fprintf(stderr, "picture published on %s: %zu bytes\n", topic_.c_str(), png.size());
  }
}

}  // namespace weedspray::fleet
