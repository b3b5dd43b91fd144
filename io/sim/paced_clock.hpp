// SPDX-License-Identifier: Apache-2.0
// Simulated time paced by CLOCK_MONOTONIC: sim time = start + speed * elapsed real time.
// speed 1 runs in real time (weedsprayd --sim), speed 10 ten times faster; several threads can
// sleep on it at once, as on the real clock.
#pragma once

#include <chrono>

#include "io/clock.hpp"

namespace weedspray::io::sim {

class PacedClock final : public Clock {
 public:
  // Throws std::invalid_argument if speed <= 0.
  explicit PacedClock(double speed = 1.0,
                      std::chrono::nanoseconds sim_start = std::chrono::nanoseconds{0});

  std::chrono::nanoseconds now() const noexcept override;
  void sleep_until(std::chrono::nanoseconds deadline) noexcept override;
  double speed() const noexcept { return speed_; }

 private:
  double speed_;
  std::chrono::nanoseconds sim_start_;
  std::chrono::nanoseconds real_start_;
};

}  // namespace weedspray::io::sim
