// SPDX-License-Identifier: Apache-2.0
// Cuts the valves' real open times and the line meter's pulses into PWM phase windows for
// control::NozzleHealth, one control cycle at a time.
//
// A window is period / nozzles long, aligned to the valve schedule's start, so with staggered
// phases each window holds a different mix of open nozzles. The open times come from the valve
// thread's written masks and the times it wrote them (io::ValvePwmStats): between two cycles the
// previous mask held until the latest write, the new one after it, so each window's open time is
// exact unless two writes fall within one cycle (2 ms: the short state in between is lost). The
// meter is read `meter_lag` after a window closes (the valves' opening and closing delays and
// the hose put the metered flow behind the writes), and the pulses since the previous read are
// that window's volume. The first window after a (re)start is partial: it only marks the meter.
//
// The daemon's control loop and the lab's closed-loop rig both cut their windows with this and
// kMeterLag. Pure (times in, windows out), fixed size: no allocation, locks or clocks.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <span>

#include "control/nozzle_health.hpp"

namespace weedspray::control {

// How long the line meter's count lags the valve writes: the valves' mean dead time (flow starts
// ~15 ms after the open command, stops ~25 ms after the close; the plant model's label valve),
// what the lab's blockage experiment names nozzles with.
inline constexpr std::chrono::nanoseconds kMeterLag{30'000'000};

class PhaseWindows {
 public:
  using Nanos = std::chrono::nanoseconds;

  PhaseWindows(Nanos window, Nanos meter_lag) noexcept : window_(window), meter_lag_(meter_lag) {}

  // Not spraying, or the valves were held closed: the next update starts afresh.
  void restart() noexcept { started_ = false; }

  // One cycle at `now`: the valve schedule's start, the mask written last and when it was
  // written, the meter's pulse count. True when a window is complete (open_s(), metered_l()).
  bool update(Nanos schedule_start, std::uint32_t mask, Nanos written_at, Nanos now,
              std::uint64_t pulses, double pulses_per_litre) noexcept;

  std::span<const double> open_s() const noexcept { return done_open_s_; }
  double metered_l() const noexcept { return done_l_; }
  double window_s() const noexcept { return std::chrono::duration<double>(window_).count(); }
  // When the closed window's liquid has passed the meter (the next update at or after it can
  // complete it); negative when none is pending.
  Nanos meter_due() const noexcept { return pending_due_; }

 private:
  using Times = std::array<double, kMaxHealthNozzles>;
  // Adds [from, to) with `mask` open, closing the windows it crosses.
  void account(Nanos from, Nanos to, std::uint32_t mask) noexcept;

  Nanos window_;
  Nanos meter_lag_;
  bool started_ = false;
  Nanos schedule_start_{};
  Nanos accounted_until_{};
  std::uint32_t mask_ = 0;
  std::int64_t index_ = 0;  // the window being filled
  Times open_s_{};
  Times pending_open_s_{};
  Nanos pending_due_{-1};      // when the closed window's liquid has passed the meter
  bool meter_marked_ = false;  // false: the first (partial) window only marks the meter
  std::uint64_t meter_mark_ = 0;
  Times done_open_s_{};
  double done_l_ = 0.0;
};

}  // namespace weedspray::control
