// SPDX-License-Identifier: Apache-2.0
#include "fleet/repeating_timer.hpp"

#include <stdexcept>
#include <string>

namespace weedspray::fleet {

RepeatingTimer::RepeatingTimer(sd_event* event, double period_s, std::uint64_t accuracy_us,
                               std::function<void()> tick, const char* what)
    : tick_(std::move(tick)) {
  if (period_s <= 0) return;
  period_us_ = static_cast<std::uint64_t>(period_s * 1e6);
  if (sd_event_add_time_relative(event, &source_, CLOCK_MONOTONIC, period_us_, accuracy_us,
                                 on_timer, this) < 0) {
    throw std::runtime_error(std::string("cannot make the ") + what + " timer");
  }
  sd_event_source_set_enabled(source_, SD_EVENT_ON);
}

RepeatingTimer::~RepeatingTimer() {
  sd_event_source_disable_unref(source_);
}

int RepeatingTimer::on_timer(sd_event_source* source, std::uint64_t, void* userdata) {
  auto* self = static_cast<RepeatingTimer*>(userdata);
  self->tick_();
  sd_event_source_set_time_relative(source, self->period_us_);
  sd_event_source_set_enabled(source, SD_EVENT_ON);
  return 0;
}

}  // namespace weedspray::fleet
