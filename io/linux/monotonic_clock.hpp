// SPDX-License-Identifier: Apache-2.0
// The hardware clock: CLOCK_MONOTONIC, sleeping with clock_nanosleep(TIMER_ABSTIME) so
// deadlines are absolute and never drift.
#pragma once

#include "io/clock.hpp"

namespace weedspray::io::hw {

class MonotonicClock final : public Clock {
 public:
  std::chrono::nanoseconds now() const noexcept override;
  void sleep_until(std::chrono::nanoseconds deadline) noexcept override;
};

// CLOCK_MONOTONIC now, for code that needs a timestamp without a Clock object.
std::chrono::nanoseconds monotonic_now() noexcept;

}  // namespace weedspray::io::hw
