// SPDX-License-Identifier: Apache-2.0
// At most one event per interval (the live view's snapshots): the interval runs from the
// last marked event; a refused request marks nothing and is told how long until one would be
// allowed.
#pragma once

#include <chrono>

namespace weedspray::daemon {

class RateLimit {
 public:
  using Nanos = std::chrono::nanoseconds;
  explicit RateLimit(Nanos min_interval) : min_interval_(min_interval) {}

  // True when `now` is at least the interval after the last mark(); else false with `wait`
  // set to the time left.
  bool allowed(Nanos now, Nanos& wait) const {
    wait = marked_ && now - last_ < min_interval_ ? min_interval_ - (now - last_) : Nanos{0};
    return wait == Nanos{0};
  }
  void mark(Nanos now) {
    marked_ = true;
    last_ = now;
  }

 private:
  Nanos min_interval_;
  Nanos last_{};
  bool marked_ = false;
};

}  // namespace weedspray::daemon
