// SPDX-License-Identifier: Apache-2.0
#include "io/linux/monotonic_clock.hpp"

#include <time.h>

#include <cerrno>

namespace weedspray::io::hw {

std::chrono::nanoseconds monotonic_now() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::chrono::seconds{ts.tv_sec} + std::chrono::nanoseconds{ts.tv_nsec};
}

std::chrono::nanoseconds MonotonicClock::now() const noexcept {
  return monotonic_now();
}

void MonotonicClock::sleep_until(std::chrono::nanoseconds deadline) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(deadline.count() / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(deadline.count() % 1'000'000'000);
  // Restart after signals: the deadline is absolute, so retrying does not drift.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace weedspray::io::hw
