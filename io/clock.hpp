// SPDX-License-Identifier: Apache-2.0
// The injected monotonic clock. Every loop sleeps to absolute deadlines on one of these, so the
// same code runs on CLOCK_MONOTONIC (hw::MonotonicClock) or on simulated time (io/sim/).
#pragma once

#include <chrono>

namespace weedspray::io {

class Clock {
 public:
  virtual ~Clock() = default;
  // Time since the CLOCK_MONOTONIC epoch (or the simulation's epoch).
  virtual std::chrono::nanoseconds now() const noexcept = 0;
  // Returns at or after `deadline` (immediately if it is already past).
  virtual void sleep_until(std::chrono::nanoseconds deadline) noexcept = 0;
};

}  // namespace weedspray::io
