// SPDX-License-Identifier: Apache-2.0
// The valve duties of one control-loop cycle, pure: each nozzle's target flow in (what the
// spray-rate law asks for the density under it at that nozzle's speed), the duties the valves
// are commanded out. The daemon's control loop calls it on real time every cycle; the lab's
// closed-loop rig calls the same step on simulated time at the same period, so every
// `weedspray-lab experiment` measures this law, quantiser, compensation and trim.
//
// Per cycle: the line pressure goes through the 0.1 s filter (PressureFilter) and, with
// pressure compensation on, the filtered value is the pressure the lines are read at (one
// noisy read must not jitter every duty); each nozzle's duty is its line's duty for the target
// flow (raw_duty_for_flow_pct, the full-open rule included), optionally snapped to the
// quantiser's levels, then clamped to the law's band with its low-duty policy; a target of 0
// or less closes the nozzle and restarts its quantiser. The flow trim (FlowTrimStep) then
// scales the modulated duties by its correction against the line meter. Not spraying: every
// duty 0, the quantisers restart and the trim holds its correction.
//
// Flows above the band: between the line's flow at the band's top (max_duty_pct) and the
// metered held-open flow no duty gives the flow (past the top the valve's closing delay eats
// the off-time, and the clamp would hold the valve open: a worn nozzle asked for 96 % of its
// held-open flow would spray 100 %). With the PWM grid known (pwm_period_s > 0 and
// schedule_time_s >= 0), such a nozzle alternates whole PWM periods between held open and
// the band's top, a share f = (target - q_top) / (q_open - q_top) of them open, chosen by an
// accumulator per nozzle so that the mean over periods is the target. The level is chosen for
// the period whose start the valve driver latches next (the one under schedule_time_s +
// cycle_s), so the duties commanded are the ones sprayed and the trim's promise follows them.
// No threads, clocks, I/O, logging or exceptions in step(); no allocation after construction.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "control/flow_trim_step.hpp"
#include "control/spray_rate_law.hpp"

namespace weedspray::control {

// Nozzles one step commands (the valve driver's limit).
inline constexpr std::size_t kMaxCommandNozzles = 32;

struct NozzleCommandConfig {
  std::size_t nozzles = 4;
  FlowTrimStepConfig trim{};
  // Time constant of the pressure the lines are compensated with.
  double compensation_filter_s = PressureFilter::kTimeConstantS;
  // Duty levels (ascending, 0..100); quantiser_level_count 0: no quantiser.
  std::array<double, DutyQuantiser::kMaxLevels> quantiser_levels_pct{};
  std::size_t quantiser_level_count = 0;
  double quantiser_hysteresis_pct = 0.0;
  // The valves' PWM grid (control/pwm_schedule.hpp): the period and each nozzle's phase offset
  // from the schedule's start; pwm_period_s 0: flows above the band are held open.
  double pwm_period_s = 0.0;
  std::array<double, kMaxCommandNozzles> phase_offset_s{};
  double cycle_s = 0.002;  // the caller's period: a command reaches the next latch within it
};

struct NozzleCommandInputs {
  double dt_s = 0.0;
  bool spraying = false;  // the law's duties; else every valve closed
  bool trim = false;      // the meter is wired and the flow trim may move the duties
  SprayLawConfig law{};   // the band, low-duty policy (live: a reload may change it)
  bool pressure_compensation = true;
  double pressure_mpa = 0.0;  // the line pressure as read this cycle
  double setpoint_mpa = 0.0;
  std::uint64_t pulses = 0;  // the meter's running count
  double pulses_per_litre = 0.0;
  std::span<const double> target_flow_l_per_min{};  // one per nozzle; <= 0: closed
  std::span<const NozzleLine> lines{};              // one per nozzle
  double schedule_time_s = -1.0;  // now since the PWM schedule's start; < 0: unknown
};

struct NozzleCommandOutputs {
  std::array<double, kMaxCommandNozzles> law_duty_pct{};  // before the trim
  std::array<double, kMaxCommandNozzles> duty_pct{};      // what the valves are commanded
  // Nozzles alternating held-open and band-top periods for a flow above the band (bit n).
  std::uint32_t alternating_mask = 0;
  double open_fraction = 0.0;              // mean commanded duty / 100
  double compensation_pressure_mpa = 0.0;  // 0: no compensation
  FlowTrimStepOutputs trim{};
};

class NozzleCommandStep {
 public:
  // Throws std::invalid_argument naming a bad field.
  explicit NozzleCommandStep(const NozzleCommandConfig& config);

  const NozzleCommandOutputs& step(const NozzleCommandInputs& in) noexcept;
  // A new meter K or nozzle line: the trim's correction was relative to the old ones.
  void reset_trim() noexcept { trim_.reset(); }

  const NozzleCommandOutputs& outputs() const noexcept { return out_; }
  std::size_t nozzles() const noexcept { return nozzles_; }

 private:
  std::size_t nozzles_;
  bool quantised_;
  std::array<DutyQuantiser, kMaxCommandNozzles> quantisers_;
  // The duty for a flow above the band, alternating by whole PWM periods; < 0: not possible.
  double alternating_duty_pct(std::size_t n, const NozzleCommandInputs& in, double target,
                              double pressure) noexcept;

  PressureFilter compensation_filter_;
  double pwm_period_s_;
  double cycle_s_;
  std::array<double, kMaxCommandNozzles> phase_offset_s_{};
  std::array<double, kMaxCommandNozzles> open_credit_{};          // periods owed held open
  std::array<std::int64_t, kMaxCommandNozzles> chosen_period_{};  // the period last chosen for
  std::array<bool, kMaxCommandNozzles> chosen_open_{};
  FlowTrimStep trim_;
  NozzleCommandOutputs out_{};
};

}  // namespace weedspray::control
