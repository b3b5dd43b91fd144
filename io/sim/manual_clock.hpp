// SPDX-License-Identifier: Apache-2.0
// Simulated time that advances when slept on, so closed loops run as fast as the CPU allows.
// Thread-safe (atomic), but meant for one loop thread or for tests that advance it by hand.
#pragma once

#include <atomic>
#include <chrono>

#include "io/clock.hpp"

namespace weedspray::io::sim {

class ManualClock final : public Clock {
 public:
  explicit ManualClock(std::chrono::nanoseconds start = std::chrono::nanoseconds{0}) noexcept
      : now_(start.count()) {}

  std::chrono::nanoseconds now() const noexcept override {
    return std::chrono::nanoseconds{now_.load(std::memory_order_acquire)};
  }
  // Jumps time forward to `deadline` (never backwards) and returns at once.
  void sleep_until(std::chrono::nanoseconds deadline) noexcept override {
    advance_to(deadline);
    sleeps_.fetch_add(1, std::memory_order_relaxed);
  }

  void advance_to(std::chrono::nanoseconds t) noexcept {
    auto current = now_.load(std::memory_order_relaxed);
    while (current < t.count() &&
           !now_.compare_exchange_weak(current, t.count(), std::memory_order_acq_rel)) {
    }
  }
  void advance(std::chrono::nanoseconds dt) noexcept { now_.fetch_add(dt.count()); }
  std::uint64_t sleep_count() const noexcept { return sleeps_.load(std::memory_order_relaxed); }

 private:
  std::atomic<std::int64_t> now_;
  std::atomic<std::uint64_t> sleeps_{0};
};

}  // namespace weedspray::io::sim
