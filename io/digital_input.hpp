// SPDX-License-Identifier: Apache-2.0
// A debounced digital input (the start/stop key). The backend watches the line on its own
// thread and publishes the debounced state.
#pragma once

#include <chrono>
#include <cstdint>

namespace weedspray::io {

struct DigitalInputSample {
  bool active = false;              // logical level after debouncing (active-low applied)
  std::chrono::nanoseconds time{};  // when the debounced state last changed
  std::uint64_t change_count = 0;   // debounced transitions since start
  std::uint64_t error_count = 0;
};

class DigitalInput {
 public:
  virtual ~DigitalInput() = default;
  // Wait-free; safe from any thread.
  virtual DigitalInputSample sample() const noexcept = 0;
};

// Pure time-based debouncer: a new level is accepted once it has held for `hold` time.
// Feed it raw edges (level + timestamp) and poll it with the current time.
class Debouncer {
 public:
  explicit Debouncer(std::chrono::nanoseconds hold, bool initial = false) noexcept
      : hold_(hold), stable_(initial), raw_(initial) {}

  // A raw level seen at `time`. Returns true if the debounced level changed.
  bool feed(bool level, std::chrono::nanoseconds time) noexcept {
    if (level != raw_) {
      raw_ = level;
      raw_since_ = time;
    }
    return settle(time);
  }
  // Re-evaluates at `now` without a new edge. Returns true if the debounced level changed.
  bool settle(std::chrono::nanoseconds now) noexcept {
    if (raw_ != stable_ && now - raw_since_ >= hold_) {
      stable_ = raw_;
      changed_at_ = now;
      return true;
    }
    return false;
  }
  bool level() const noexcept { return stable_; }
  std::chrono::nanoseconds changed_at() const noexcept { return changed_at_; }
  // When settle() could next change the level (for sleeping), if a change is pending.
  bool pending() const noexcept { return raw_ != stable_; }
  std::chrono::nanoseconds pending_until() const noexcept { return raw_since_ + hold_; }

 private:
  std::chrono::nanoseconds hold_;
  bool stable_;
  bool raw_;
  std::chrono::nanoseconds raw_since_{};
  std::chrono::nanoseconds changed_at_{};
};

}  // namespace weedspray::io
