// SPDX-License-Identifier: Apache-2.0
#include "control/pressure_loop_step.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace weedspray::control {
namespace {

PressureLoopConfig loop_config() {
  PressureLoopConfig config;
  config.mode = PressureControlMode::kPid;
  config.controller.base.gains = {0.8, 2.0, 0.0};
  config.controller.base.output_min = 0.0;
  config.controller.base.output_max = 1.0;
  config.period_s = 0.01;
  return config;
}

PressureLoopInputs running(double pressure_mpa) {
  PressureLoopInputs in;
  in.pressure_mpa = pressure_mpa;
  in.sensor_ok = true;
  in.setpoint_mpa = 0.3;
  in.over_pressure_mpa = 0.9;
  in.pump_enabled = true;
  return in;
}

TEST(PressureLoopStep, RunsTheControllerOnAGoodReading) {
  PressureLoopStep step(loop_config());
  PressureController reference(PressureControlMode::kPid, loop_config().controller);
  reference.enable(0.0, 0.3, 0.1);
  for (int i = 0; i < 50; ++i) {
    const PressureLoopOutputs& out = step.step(running(0.1));
    EXPECT_TRUE(out.run);
    EXPECT_FALSE(out.hold_valves);
    ASSERT_DOUBLE_EQ(out.closure, reference.update(0.3, 0.1, 0.01));
  }
  EXPECT_GT(step.outputs().closure, 0.0);
}

TEST(PressureLoopStep, ASensorFaultHoldsTheValvesAndOpensTheReturnValve) {
  PressureLoopStep step(loop_config());
  for (int i = 0; i < 20; ++i) step.step(running(0.1));
  PressureLoopInputs fault = running(0.1);
  fault.sensor_ok = false;
  const PressureLoopOutputs& out = step.step(fault);
  EXPECT_FALSE(out.run);
  EXPECT_TRUE(out.hold_valves);
  EXPECT_DOUBLE_EQ(out.closure, 0.0);
  EXPECT_DOUBLE_EQ(out.pressure_mpa, 0.0);
  EXPECT_FALSE(step.controller().enabled());
  EXPECT_FALSE(out.tripped);  // a fault is no pressure, so no trip
}

TEST(PressureLoopStep, AnOverPressureTripLatchesUntilReset) {
  PressureLoopStep step(loop_config());
  step.step(running(0.3));
  EXPECT_TRUE(step.step(running(0.95)).tripped);
  const PressureLoopOutputs& after = step.step(running(0.3));
  EXPECT_TRUE(after.tripped);
  EXPECT_TRUE(after.hold_valves);
  EXPECT_FALSE(after.run);
  PressureLoopInputs reset = running(0.3);
  reset.trip_reset = 1;
  const PressureLoopOutputs& cleared = step.step(reset);
  EXPECT_FALSE(cleared.tripped);
  EXPECT_TRUE(cleared.run);
}

TEST(PressureLoopStep, AStalledValveThreadOrAnEmergencyStopStopsThePumpOnly) {
  PressureLoopStep step(loop_config());
  PressureLoopInputs in = running(0.2);
  in.valves_stalled = true;
  EXPECT_FALSE(step.step(in).run);
  EXPECT_FALSE(step.outputs().hold_valves);
  in.valves_stalled = false;
  in.estop_held = true;
  EXPECT_FALSE(step.step(in).run);
  in.estop_held = false;
  in.pump_enabled = false;
  EXPECT_FALSE(step.step(in).run);
}

TEST(PressureLoopStep, RejectsABadPeriod) {
  PressureLoopConfig config = loop_config();
  config.period_s = 0.0;
  EXPECT_THROW(PressureLoopStep{config}, std::invalid_argument);
}

}  // namespace
}  // namespace weedspray::control
