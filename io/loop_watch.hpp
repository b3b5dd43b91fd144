// SPDX-License-Identifier: Apache-2.0
// One real-time loop watching another's progress counter (cycles, wakes): stale when the
// counter has not moved for `timeout`. The valve thread watches the pressure loop (a stalled
// pressure loop must not leave the pump running against closed valves) and the pressure loop
// watches the valve thread. Allocation- and lock-free; used by one thread.
#pragma once

#include <chrono>
#include <cstdint>

namespace weedspray::io {

class LoopWatch {
 public:
  explicit LoopWatch(std::chrono::nanoseconds timeout) noexcept : timeout_(timeout) {}

  // Feeds the watched loop's counter as seen at `now`; true while it has been still too long.
  bool stale(std::uint64_t counter, std::chrono::nanoseconds now) noexcept {
    if (!seen_ || counter != last_) {
      seen_ = true;
      last_ = counter;
      changed_at_ = now;
      return false;
    }
    return now - changed_at_ > timeout_;
  }

 private:
  std::chrono::nanoseconds timeout_;
  std::chrono::nanoseconds changed_at_{0};
  std::uint64_t last_ = 0;
  bool seen_ = false;
};

}  // namespace weedspray::io
