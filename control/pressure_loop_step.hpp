// SPDX-License-Identifier: Apache-2.0
// One cycle of the pressure loop, pure: the pressure reading and the operator's wishes in, the
// pump and return-valve commands and the valve hold out. The daemon's ws-pressure thread reads
// the converters and calls it on real time; the lab's closed-loop rig calls the same step on
// simulated time against the plant model, so the lab's pressure figures are the daemon's loop.
//
// Rules (SPEC §4): a reading that is no pressure (outside the 4-20 mA fault limits, or stale)
// or a pressure above the trip limit holds the nozzle valves closed; a trip stays latched until
// trip_reset changes. The pump runs and the controller drives the return valve only while the
// pump is wanted, the reading is good, nothing tripped, the valve thread runs and no emergency
// stop is latched; otherwise the return valve opens fully (closure 0, the safe state) and the
// controller is disabled, to start again bumplessly from a fully open valve.
// No threads, clocks, I/O, logging or exceptions in step(); no allocation after construction.
#pragma once

#include <cstdint>

#include "control/pressure_controller.hpp"

namespace weedspray::control {

struct PressureLoopConfig {
  PressureControlMode mode = PressureControlMode::kFuzzyPid;
  FuzzyPidConfig controller{};
  double period_s = 0.01;  // the loop's period: the controller's dt
};

struct PressureLoopInputs {
  double pressure_mpa = 0.0;  // the converted reading; used only when sensor_ok
  bool sensor_ok = false;     // a fresh sample inside the sensor's fault limits
  double setpoint_mpa = 0.0;
  double over_pressure_mpa = 1.0;  // above it: trip
  bool pump_enabled = false;
  std::uint64_t trip_reset = 0;  // a change clears a latched trip
  bool valves_stalled = false;   // the valve thread stopped advancing
  bool estop_held = false;       // the emergency stop's latch
};

struct PressureLoopOutputs {
  double pressure_mpa = 0.0;  // the reading used (0 when it is no pressure)
  bool run = false;           // pump on, return valve driven to closure
  double closure = 0.0;       // return-valve closure 0..1 (0: fully open)
  bool hold_valves = false;   // no pressure reading or a trip: nozzle valves held closed
  bool tripped = false;       // over-pressure trip latched
};

class PressureLoopStep {
 public:
  // Throws std::invalid_argument on a bad controller config or period.
  explicit PressureLoopStep(const PressureLoopConfig& config);

  const PressureLoopOutputs& step(const PressureLoopInputs& in) noexcept;

  const PressureLoopOutputs& outputs() const noexcept { return out_; }
  const PressureController& controller() const noexcept { return controller_; }
  const PressureLoopConfig& config() const noexcept { return config_; }

 private:
  PressureLoopConfig config_;
  PressureController controller_;
  PressureLoopOutputs out_{};
  bool started_ = false;
  std::uint64_t trip_reset_seen_ = 0;
};

}  // namespace weedspray::control
