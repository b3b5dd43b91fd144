// SPDX-License-Identifier: Apache-2.0
#include "control/phase_windows.hpp"

#include <algorithm>

namespace weedspray::control {

void PhaseWindows::account(Nanos from, Nanos to, std::uint32_t mask) noexcept {
  while (from < to) {
    const std::int64_t index = (from - schedule_start_) / window_;
    if (index != index_) {  // the window closed: its liquid reaches the meter a lag later
      // One still waiting for the meter (a cycle late by more than a window): both would share
      // one count, so neither is used; the next read only marks the meter.
      if (pending_due_.count() >= 0) meter_marked_ = false;
      pending_open_s_ = open_s_;
      pending_due_ = schedule_start_ + (index_ + 1) * window_ + meter_lag_;
      open_s_.fill(0.0);
      index_ = index;
    }
    const Nanos end = std::min(to, schedule_start_ + (index + 1) * window_);
    const double s = std::chrono::duration<double>(end - from).count();
    for (std::size_t i = 0; i < open_s_.size(); ++i)
      if (mask & (1U << i)) open_s_[i] += s;
    from = end;
  }
  accounted_until_ = std::max(accounted_until_, to);
}

bool PhaseWindows::update(Nanos schedule_start, std::uint32_t mask, Nanos written_at, Nanos now,
                          std::uint64_t pulses, double pulses_per_litre) noexcept {
  if (!started_ || schedule_start != schedule_start_) {
    started_ = true;
    schedule_start_ = schedule_start;
    accounted_until_ = std::max(now, schedule_start);
    mask_ = mask;
    index_ = (accounted_until_ - schedule_start_) / window_;
    open_s_.fill(0.0);
    pending_due_ = Nanos{-1};
    meter_marked_ = false;
    return false;
  }
  // The previous mask held until this write (a write already accounted for: from now on).
  if (written_at > accounted_until_) account(accounted_until_, std::min(written_at, now), mask_);
  mask_ = mask;
  account(accounted_until_, now, mask_);
  if (pending_due_.count() < 0 || now < pending_due_) return false;
  pending_due_ = Nanos{-1};
  const bool complete = meter_marked_;
  if (complete) {
    done_open_s_ = pending_open_s_;
    done_l_ = static_cast<double>(pulses - meter_mark_) / pulses_per_litre;
  }
  meter_marked_ = true;
  meter_mark_ = pulses;
  return complete;
}

}  // namespace weedspray::control
