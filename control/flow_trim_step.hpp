// SPDX-License-Identifier: Apache-2.0
// The flow trim's share of one control-loop cycle, pure: the duties the spray-rate law chose in,
// the trimmed duties out, with the meter read against what the lines promise at them. The
// daemon's control loop calls it on real time; the lab's closed-loop rig calls the same step on
// simulated time, so `weedspray-lab experiment orthogonal` measures this trim.
//
// Per cycle: the pressure goes through the 0.1 s filter (PressureFilter: one noisy read off the
// set-point must not freeze a whole window); the modulated duties (0 < d < 100) are scaled by
// the trim's correction in flow (trimmed_duty_pct) and kept inside the law's band; the cycle's
// promise at the trimmed duties, the open fraction, the filtered pressure's error and the meter
// count go to FlowTrimWindows (a window with a nozzle held open at a line without a measured
// full-open flow is unusable: FlowTrimInput::promise_known), whose windows update FlowTrim and the
// slower CalibrationRatio. Not spraying (or no meter): the windows and the filter start afresh, the
// correction holds. No threads, clocks, I/O, logging or exceptions in step(); no allocation after
// construction.
#pragma once

#include <cstdint>
#include <span>

#include "control/flow_feedback.hpp"
#include "control/spray_rate_law.hpp"

namespace weedspray::control {

// First-order low-pass of the line pressure with the control loops' 0.1 s time constant: what
// the trim judges the set-point by, and what the lab's rig compensates duties with.
class PressureFilter {
 public:
  static constexpr double kTimeConstantS = 0.1;
  explicit PressureFilter(double time_constant_s = kTimeConstantS) noexcept
      : time_constant_s_(time_constant_s) {}
  // The first update after construction or reset() takes the reading as it is.
  double update(double pressure_mpa, double dt_s) noexcept;
  void reset() noexcept { started_ = false; }
  double value() const noexcept { return value_; }

 private:
  double time_constant_s_;
  bool started_ = false;
  double value_ = 0.0;
};

struct FlowTrimStepConfig {
  FlowTrimConfig trim{};
  double window_s = 1.0;  // meter windows (whole PWM periods at whole Hz)
  double pressure_filter_s = PressureFilter::kTimeConstantS;
};

struct FlowTrimStepInputs {
  double dt_s = 0.0;
  bool spraying = false;  // the law's duties, the meter wired: else the trim holds
  double pressure_mpa = 0.0;
  double setpoint_mpa = 0.0;
  double compensation_pressure_mpa = 0.0;  // 0: no pressure compensation
  std::uint64_t pulses = 0;                // the meter's running count
  double pulses_per_litre = 0.0;
  // The law's duties before the trim, one per nozzle, trimmed in place.
  std::span<double> duty_pct{};
  std::span<const NozzleLine> lines{};
  double min_duty_pct = 0.0;  // the law's band a trimmed modulated duty stays in
  double max_duty_pct = 100.0;
};

struct FlowTrimStepOutputs {
  double correction = 1.0;
  bool active = false;  // spraying and the last window usable
  double calibration_ratio = 1.0;
  bool calibration_ratio_known = false;
};

class FlowTrimStep {
 public:
  // Throws std::invalid_argument naming a bad field.
  explicit FlowTrimStep(const FlowTrimStepConfig& config = {});

  const FlowTrimStepOutputs& step(const FlowTrimStepInputs& in) noexcept;
  // A new meter K or nozzle line: the correction was relative to the old ones.
  void reset() noexcept;

  const FlowTrimStepOutputs& outputs() const noexcept { return out_; }
  double correction() const noexcept { return trim_.correction(); }

 private:
  FlowTrimStepConfig config_;
  FlowTrimWindows windows_;
  FlowTrim trim_;
  CalibrationRatio calibration_ratio_;
  PressureFilter pressure_;
  FlowTrimStepOutputs out_{};
};

}  // namespace weedspray::control
