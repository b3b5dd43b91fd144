// SPDX-License-Identifier: Apache-2.0
#include "io/sim/paced_clock.hpp"

#include <time.h>

#include <cerrno>
#include <cmath>
#include <stdexcept>
#include <string>

namespace weedspray::io::sim {
namespace {

std::chrono::nanoseconds real_now() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::chrono::seconds{ts.tv_sec} + std::chrono::nanoseconds{ts.tv_nsec};
}

}  // namespace

PacedClock::PacedClock(double speed, std::chrono::nanoseconds sim_start)
    : speed_(speed), sim_start_(sim_start), real_start_(real_now()) {
  if (!(speed > 0.0) || !std::isfinite(speed))
    throw std::invalid_argument("PacedClock: speed must be > 0, got " + std::to_string(speed));
}

std::chrono::nanoseconds PacedClock::now() const noexcept {
  const double elapsed = static_cast<double>((real_now() - real_start_).count()) * speed_;
  return sim_start_ + std::chrono::nanoseconds{static_cast<std::int64_t>(elapsed)};
}

void PacedClock::sleep_until(std::chrono::nanoseconds deadline) noexcept {
  const double sim_elapsed = static_cast<double>((deadline - sim_start_).count());
  const std::chrono::nanoseconds real_deadline =
      real_start_ +
      std::chrono::nanoseconds{static_cast<std::int64_t>(std::ceil(sim_elapsed / speed_))};
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(real_deadline.count() / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(real_deadline.count() % 1'000'000'000);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace weedspray::io::sim
