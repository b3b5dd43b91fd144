// SPDX-License-Identifier: Apache-2.0
// A callback every period on the main sd-event loop (CLOCK_MONOTONIC), armed again after each
// run, so a slow callback delays the next one rather than piling them up.
#pragma once

#include <cstdint>
#include <functional>

#include <systemd/sd-event.h>

namespace weedspray::fleet {

class RepeatingTimer {
 public:
  // period_s <= 0: never. accuracy_us: how late sd-event may run it (0: its default, 250 ms,
  // which lets it bunch timers). Throws std::runtime_error naming `what` when it cannot be made.
  RepeatingTimer(sd_event* event, double period_s, std::uint64_t accuracy_us,
                 std::function<void()> tick, const char* what);
  ~RepeatingTimer();
  RepeatingTimer(const RepeatingTimer&) = delete;
  RepeatingTimer& operator=(const RepeatingTimer&) = delete;

 private:
  static int on_timer(sd_event_source* source, std::uint64_t, void* userdata);

  std::function<void()> tick_;
  std::uint64_t period_us_ = 0;
  sd_event_source* source_ = nullptr;
};

}  // namespace weedspray::fleet
