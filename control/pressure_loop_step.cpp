// SPDX-License-Identifier: Apache-2.0
#include "control/pressure_loop_step.hpp"

#include <cmath>
#include <stdexcept>

namespace weedspray::control {

PressureLoopStep::PressureLoopStep(const PressureLoopConfig& config)
    : config_(config), controller_(config.mode, config.controller) {
  if (!(std::isfinite(config.period_s) && config.period_s > 0.0 && config.period_s <= 0.1))
    throw std::invalid_argument("PressureLoopConfig.period_s must be in (0, 0.1]");
  // The first run starts bumplessly from the fully open return valve, as every later one does
  // (the gains were tuned on such start-ups).
  controller_.disable();
}

const PressureLoopOutputs& PressureLoopStep::step(const PressureLoopInputs& in) noexcept {
  if (!started_ || in.trip_reset != trip_reset_seen_) {
    if (started_) out_.tripped = false;
    started_ = true;
    trip_reset_seen_ = in.trip_reset;
  }
  out_.pressure_mpa = in.sensor_ok ? in.pressure_mpa : 0.0;
  // Over-pressure: pump off in this very cycle.
  if (in.sensor_ok && in.pressure_mpa > in.over_pressure_mpa) out_.tripped = true;
  out_.hold_valves = !in.sensor_ok || out_.tripped;
  out_.run =
      in.pump_enabled && in.sensor_ok && !out_.tripped && !in.valves_stalled && !in.estop_held;
  if (out_.run) {
    if (!controller_.enabled()) controller_.enable(0.0, in.setpoint_mpa, in.pressure_mpa);
    out_.closure = controller_.update(in.setpoint_mpa, in.pressure_mpa, config_.period_s);
  } else {
    controller_.disable();
    out_.closure = 0.0;
  }
  return out_;
}

}  // namespace weedspray::control
