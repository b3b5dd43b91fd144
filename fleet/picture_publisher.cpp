// SPDX-License-Identifier: Apache-2.0
#include "fleet/picture_publisher.hpp"

#include <cstdio>
#include <stdexcept>

namespace weedspray::fleet {

PicturePublisher::PicturePublisher(sd_event* event, double interval_s, DaemonClient& daemon,
                                   MqttLink& mqtt, const Topics& topics)
    : daemon_(daemon), mqtt_(mqtt), topic_(topics.board("picture")) {
  if (interval_s <= 0) return;
  interval_us_ = static_cast<std::uint64_t>(interval_s * 1e6);
  if (sd_event_add_time_relative(event, &timer_, CLOCK_MONOTONIC, interval_us_, 0, on_timer, this) <
      0) {
    throw std::runtime_error("cannot make the picture timer");
  }
  sd_event_source_set_enabled(timer_, SD_EVENT_ON);
}

PicturePublisher::~PicturePublisher() {
  sd_event_source_disable_unref(timer_);
}

int PicturePublisher::on_timer(sd_event_source* source, std::uint64_t, void* userdata) {
  auto* self = static_cast<PicturePublisher*>(userdata);
  self->take();
  sd_event_source_set_time_relative(source, self->interval_us_);
  sd_event_source_set_enabled(source, SD_EVENT_ON);
  return 0;
}

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
