// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include "daemon/supervision/state_machine.hpp"

namespace weedspray::daemon {
namespace {

TEST(StateMachine, StartsInStartingWithEverythingOff) {
  StateMachine sm;
  EXPECT_EQ(sm.state(), SprayerState::kStarting);
  EXPECT_FALSE(sm.valves_enabled());
  EXPECT_FALSE(sm.pump_enabled());
  const Transition t = sm.handle(StateEvent::kStart);
  EXPECT_FALSE(t.accepted);
  EXPECT_EQ(t.reason, "still starting up");
}

TEST(StateMachine, IdleSprayingIdle) {
  StateMachine sm;
  EXPECT_TRUE(sm.handle(StateEvent::kSetupDone).accepted);
  EXPECT_EQ(sm.state(), SprayerState::kIdle);
  EXPECT_FALSE(sm.pump_enabled()) << "Idle: pump off";
  EXPECT_FALSE(sm.valves_enabled());
  EXPECT_TRUE(sm.handle(StateEvent::kStart).accepted);
  EXPECT_TRUE(sm.valves_enabled());
  EXPECT_TRUE(sm.pump_enabled());
  EXPECT_FALSE(sm.handle(StateEvent::kStart).accepted);
  EXPECT_TRUE(sm.handle(StateEvent::kStop).accepted);
  EXPECT_EQ(sm.state(), SprayerState::kIdle);
  EXPECT_FALSE(sm.pump_enabled());
  EXPECT_FALSE(sm.handle(StateEvent::kStop).accepted);
}

TEST(StateMachine, KeyToggles) {
  StateMachine sm;
  sm.handle(StateEvent::kSetupDone);
  sm.handle(StateEvent::kKeyPressed);
  EXPECT_EQ(sm.state(), SprayerState::kSpraying);
  sm.handle(StateEvent::kKeyPressed);
  EXPECT_EQ(sm.state(), SprayerState::kIdle);
}

TEST(StateMachine, FaultLatchesSafeUntilAlarmsCleared) {
  StateMachine sm;
  sm.handle(StateEvent::kSetupDone);
  sm.handle(StateEvent::kStart);
  EXPECT_TRUE(sm.handle(StateEvent::kFault).accepted);
  EXPECT_FALSE(sm.valves_enabled());
  EXPECT_FALSE(sm.pump_enabled());
  const Transition start = sm.handle(StateEvent::kStart);
  EXPECT_FALSE(start.accepted);
  EXPECT_EQ(start.reason, "in Fault: clear the alarms first");
  EXPECT_FALSE(sm.handle(StateEvent::kKeyPressed).accepted);
  EXPECT_EQ(sm.state(), SprayerState::kFault);
  EXPECT_TRUE(sm.handle(StateEvent::kAlarmsCleared).accepted);
  EXPECT_EQ(sm.state(), SprayerState::kIdle);
}

TEST(StateMachine, ACalibrationRunsThePumpInIdleOnlyNeverInFault) {
  StateMachine sm;
  EXPECT_FALSE(sm.pump_enabled(true)) << "Starting: pump off even for a calibration";
  sm.handle(StateEvent::kSetupDone);
  EXPECT_TRUE(sm.pump_enabled(true)) << "Idle: a calibration runs the pump";
  EXPECT_FALSE(sm.valves_enabled());
  // A Fault during the calibration: the pump is off at once, whatever the calibration asks.
  EXPECT_TRUE(sm.handle(StateEvent::kFault).accepted);
  EXPECT_FALSE(sm.pump_enabled(true));
  EXPECT_FALSE(sm.valves_enabled());
}

TEST(StateMachine, FaultDuringStartup) {
  StateMachine sm;
  EXPECT_TRUE(sm.handle(StateEvent::kFault).accepted);
  EXPECT_FALSE(sm.handle(StateEvent::kSetupDone).accepted);
  EXPECT_EQ(sm.state(), SprayerState::kFault);
}

}  // namespace
}  // namespace weedspray::daemon
