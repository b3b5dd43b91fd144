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
};

struct NozzleCommandOutputs {
  std::array<double, kMaxCommandNozzles> law_duty_pct{};  // before the trim
  std::array<double, kMaxCommandNozzles> duty_pct{};      // what the valves are commanded
  double open_fraction = 0.0;                             // mean commanded duty / 100
  double compensation_pressure_mpa = 0.0;                 // 0: no compensation
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
  PressureFilter compensation_filter_;
  FlowTrimStep trim_;
  NozzleCommandOutputs out_{};
};

}  // namespace weedspray::control
