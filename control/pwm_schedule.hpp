// SPDX-License-Identifier: Apache-2.0
// Staggered-period PWM for up to 32 solenoid valves (SPEC §3, UGV paper dong2024 §3.2).
//
// Every valve runs a period T = 1/frequency (1..20 Hz, rounded to whole nanoseconds). In the
// staggered mode the valve in slot k of `order` starts its periods k*T/N after start(), so the
// valves do not open together; outer-first order (A D B C for four valves) disturbed the inner
// nozzles least in the paper. In the synchronous mode all periods start together (for the
// comparison). Each valve opens at its period start and closes after duty*T; the duty set with
// set_duty() is latched only at that valve's next period start (latched mode).
// Immediate mode (PwmConfig.immediate_start_stop, used by the daemon so spray lands on the imaged
// ground): set_duty(valve, duty, now) on a CLOSED valve (closed for its whole current period)
// with duty > 0 starts a new period at once — at now, or later only as far as min_off_time since
// the valve closed requires. That first period is stretched or shortened (to between T/2 and
// 3T/2, its on-time duty x its length) so that it ends on the valve's own stagger grid: the
// periods after it keep their slot. (Without this, valves started together — at Start, after a
// weed-free stretch — stayed in phase for good, and the daemon's PWM was synchronous.) A duty
// of 0 on an OPEN valve closes it at once (at now, or at period start +
// min_on_time if later). Other duty changes are still latched at the next period start.
// Minimum on/off time: a pulse whose on part would be shorter than min_on_time is rounded to
// the NEARER of 0 (closed all period) and min_on_time; an off part shorter than min_off_time
// to the nearer of 0 (open all period) and min_off_time. This keeps the mean flow error of a
// rounded duty below half a minimum pulse. Requires min_on + min_off <= T.
// Output: the exact edge times. next_edge() returns the next instant at which any valve's state
// changes or any valve's period starts (so a duty change is latched on time even when the mask
// does not change), with the mask of ALL valves after the edge (bit i = valve i open); edges of
// several valves at the same instant are merged. The io layer sleeps until edge.time and
// writes edge.valve_mask. All arithmetic is integer nanoseconds: no drift over hours.
// Pure and allocation-free after construction: the I/O thread owns the object.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace weedspray::control {

inline constexpr std::size_t kMaxPwmValves = 32;

struct PwmEdge {
  std::chrono::nanoseconds time{0};
  std::uint32_t valve_mask = 0;  // state of all valves after the edge, bit i = valve i open
};

enum class PwmPhaseMode { kStaggered, kSynchronous };

struct PwmConfig {
  std::size_t valve_count = 4;  // 1..32
  double frequency_hz = 5.0;    // 1..20
  PwmPhaseMode phase_mode = PwmPhaseMode::kStaggered;
  // order[k] = the valve whose period starts at offset k*T/N. Empty = outer_first_order(N).
  // Must be a permutation of 0..N-1.
  std::vector<std::size_t> order{};
  std::chrono::nanoseconds min_on_time{0};
  std::chrono::nanoseconds min_off_time{0};
  // false: latched mode (duty changes only at period starts); true: immediate mode (above).
  bool immediate_start_stop = false;
};

// Outer-first stagger order: 0, N-1, 1, N-2, ... (for N = 4: A D B C).
std::vector<std::size_t> outer_first_order(std::size_t valve_count);

// What one valve does in the period that contains a given time.
struct PwmValveState {
  bool open = false;
  double latched_duty_pct = 0.0;  // requested duty latched at this period's start
  std::chrono::nanoseconds period_start{0};
  std::chrono::nanoseconds on_time{0};  // after min-on/min-off rounding
};

class PwmSchedule {
 public:
  // Throws std::invalid_argument naming the field.
  explicit PwmSchedule(const PwmConfig& config);

  // Reset the cursor to t0: all valves closed, no period latched yet; the first period of the
  // valve in slot k starts at t0 + k*T/N (t0 for all in the synchronous mode). Requested duties
  // are kept.
  void start(std::chrono::nanoseconds t0) noexcept;

  // Requested duty in percent, clamped to [0, 100] (NaN -> 0); latched at the valve's next
  // period start. Out-of-range valve index is ignored.
  // In immediate mode, `now` (>= the last edge time; earlier is treated as it) is when the
  // change is requested: a start/stop happens at or after it, never before. The overloads
  // without `now` use the last edge time.
  void set_duty(std::size_t valve, double duty_pct) noexcept;
  void set_duties(std::span<const double> duty_pct) noexcept;
  void set_duty(std::size_t valve, double duty_pct, std::chrono::nanoseconds now) noexcept;
  void set_duties(std::span<const double> duty_pct, std::chrono::nanoseconds now) noexcept;
  // Close everything NOW: all requested and latched duties -> 0; returns the mask to write (0).
  // The following edges keep every valve closed until new duties are set.
  std::uint32_t force_closed() noexcept;

  // Advance the cursor to the next edge and return it: strictly after the previous one, except
  // that an immediate start/stop requested at exactly the last edge time lies at that time.
  PwmEdge next_edge() noexcept;
  // The edge next_edge() would return now, without advancing (the io layer peeks so a duty
  // change made before the edge is due is reflected in it).
  PwmEdge peek_edge() const noexcept;
  // Time of the last edge returned (t0 right after start()).
  std::chrono::nanoseconds last_edge_time() const noexcept { return cursor_; }

  // Mask and per-valve state at time t, for t in [time of the last returned edge, time of the
  // next one) — i.e. the interval the io layer is in. Exact for that interval.
  std::uint32_t current_mask() const noexcept { return mask_; }
  PwmValveState valve_state(std::size_t valve) const noexcept;
  // State at any time t from the valve's current period start on: exact inside the current
  // period; in later periods a prediction that assumes the duty requested now is latched
  // (exact as long as set_duty is not called again). Before the current period: the current
  // period's state is not history, so t is treated as the current period start.
  PwmValveState valve_state_at(std::size_t valve, std::chrono::nanoseconds t) const noexcept;
  std::uint32_t mask_at(std::chrono::nanoseconds t) const noexcept;

  // Pulse on-time for a duty after the min-on/min-off rounding (pure helper), in a period of the
  // schedule's length or of `length` (an immediate start's first period).
  std::chrono::nanoseconds on_time_for(double duty_pct) const noexcept;
  std::chrono::nanoseconds on_time_for(double duty_pct,
                                       std::chrono::nanoseconds length) const noexcept;
  // Effective duty after rounding, in percent.
  double effective_duty_pct(double duty_pct) const noexcept;

  std::chrono::nanoseconds period() const noexcept { return period_; }
  std::chrono::nanoseconds phase_offset(std::size_t valve) const noexcept;
  std::size_t valve_count() const noexcept { return valve_count_; }

 private:
  struct Valve {
    std::chrono::nanoseconds offset{0};
    std::chrono::nanoseconds grid_origin{0};        // start() time + offset: its slot's grid
    std::chrono::nanoseconds period_start{0};       // start of the current period
    std::chrono::nanoseconds next_period_start{0};  // start of the next period
    std::chrono::nanoseconds on_time{0};            // of the current period
    std::chrono::nanoseconds closed_at{0};          // last open -> closed edge (min off-time)
    std::chrono::nanoseconds opened_at{0};          // last closed -> open edge (min on-time)
    bool started = false;                           // first period has begun
    double requested_duty_pct = 0.0;
    double latched_duty_pct = 0.0;
  };

  std::size_t valve_count_;
  std::chrono::nanoseconds period_;
  std::chrono::nanoseconds min_on_;
  std::chrono::nanoseconds min_off_;
  std::chrono::nanoseconds close_time(std::size_t valve) const noexcept;
  // The first point of the valve's slot grid at or after `t` + max(T/2, min_on + min_off): where
  // a period starting at `t` ends (t + T when t is on the grid).
  std::chrono::nanoseconds period_end_on_grid(const Valve& valve,
                                              std::chrono::nanoseconds t) const noexcept;
  std::chrono::nanoseconds next_event_time() const noexcept;

  bool immediate_;
  std::array<Valve, kMaxPwmValves> valves_{};
  std::chrono::nanoseconds cursor_{0};
  std::uint32_t mask_ = 0;
};

}  // namespace weedspray::control
