// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <thread>

#include "io/digital_input.hpp"
#include "io/signal_conversion.hpp"
#include "io/sim/manual_clock.hpp"
#include "io/sim/manual_digital_input.hpp"
#include "io/sim/memory_output_bank.hpp"
#include "io/sim/paced_clock.hpp"
#include "io/sim/simulated_machine.hpp"

namespace weedspray::io::sim {
namespace {

using namespace std::chrono_literals;
using std::chrono::nanoseconds;

struct SimMachine {
  ManualClock clock;
  SimulatedMachine machine{SimulatedMachineConfig{}, clock};
  SimulatedValveBank valves{machine};
  SimulatedPumpRelay pump{machine};
  SimulatedPressureAdc adc{machine, clock};
  ValveDriveConfig drive{};
  SimulatedReturnValveDac dac{machine, drive};
  SimulatedPulseInput flow{machine, SimulatedPulseSource::kFlowMeter};
  SimulatedPulseInput wheel{machine, SimulatedPulseSource::kWheel};
  SimulatedTankLevel tank{machine, clock};
  CurrentLoopSensorConfig sensor{};
};

TEST(SimRig, PumpAndClosedReturnValveBuildPressureSeenThroughTheAdc) {
  SimMachine m;
  const auto idle = pressure_from_sensor_volts(m.adc.read().volts, m.sensor);
  ASSERT_TRUE(idle.ok()) << "4 mA at rest is a valid reading";
  EXPECT_NEAR(idle.pressure_mpa, 0.0, 0.02);

  m.pump.write(1);
  m.dac.write(0.4);  // return valve mostly closed
  m.clock.advance(3s);
  const AnalogSample s = m.adc.read();
  EXPECT_TRUE(s.ok);
  EXPECT_EQ(s.time, 3s);
  const auto p = pressure_from_sensor_volts(s.volts, m.sensor);
  ASSERT_TRUE(p.ok());
  double true_p = 0;
  m.machine.with_plant([&](auto& plant) { true_p = plant.line_pressure_mpa(); });
  EXPECT_GT(true_p, 0.2);
  EXPECT_NEAR(p.pressure_mpa, true_p, 0.02);

  // Opening the return valve (safe value) lowers the pressure.
  m.dac.force_safe();
  EXPECT_NEAR(m.dac.last_volts(), 3.3, 1e-9);
  m.clock.advance(3s);
  EXPECT_LT(pressure_from_sensor_volts(m.adc.read().volts, m.sensor).pressure_mpa, true_p * 0.6);
}

TEST(SimRig, OpenValvesMakeFlowPulsesWithTimestamps) {
  SimMachine m;
  m.pump.write(1);
  m.dac.write(0.5);
  m.clock.advance(2s);
  const PulseSnapshot before = m.flow.snapshot();
  m.valves.write(0xF);
  EXPECT_EQ(m.valves.mask(), 0xFU);
  m.clock.advance(2s);
  const PulseSnapshot after = m.flow.snapshot();
  EXPECT_GT(after.count, before.count + 100) << "4 open nozzles at pressure: hundreds of pulses";
  EXPECT_GT(after.last_edge_time, 3900ms);
  EXPECT_LE(after.last_edge_time, 4s);
  EXPECT_EQ(after.error_count, 0U);

  m.valves.force_safe();
  EXPECT_EQ(m.valves.mask(), 0U) << "every valve ended closed";
  m.pump.force_safe();
  EXPECT_FALSE(m.machine.pump_on());
}

TEST(SimRig, WheelPulsesFollowGroundSpeedAndTankDrains) {
  SimMachine m;
  m.machine.with_plant([](auto& plant) { plant.set_ground_speed(2.0); });
  m.clock.advance(5s);
  const PulseSnapshot w = m.wheel.snapshot();
  // 10 m at the default 20 pulses/m.
  EXPECT_NEAR(static_cast<double>(w.count), 200.0, 2.0);

  const TankLevelSample full = m.tank.read();
  ASSERT_TRUE(full.ok);
  m.pump.write(1);
  m.valves.write(0xF);
  m.dac.write(0.3);
  m.clock.advance(20s);
  const TankLevelSample later = m.tank.read();
  ASSERT_TRUE(later.ok);
  EXPECT_LT(later.level_pct, full.level_pct - 1.0);
  EXPECT_EQ(later.reads, 2U);

  m.tank.inject_timeouts(2);
  EXPECT_FALSE(m.tank.read().ok);
  const TankLevelSample t = m.tank.read();
  EXPECT_FALSE(t.ok);
  EXPECT_EQ(t.timeouts, 2U);
  EXPECT_TRUE(m.tank.read().ok);
}

TEST(SimRig, FollowsTheClockLazily) {
  SimMachine m;
  m.clock.advance(1500ms);
  m.machine.advance();
  EXPECT_EQ(m.machine.plant_time(), 1500ms);
  double t = 0;
  m.machine.with_plant([&](auto& plant) { t = plant.time_s(); });
  EXPECT_NEAR(t, 1.5, 1e-6);
}

TEST(ManualClock, AdvancesWhenSleptOnNeverBackwards) {
  ManualClock clock(5s);
  clock.sleep_until(7s);
  EXPECT_EQ(clock.now(), 7s);
  clock.sleep_until(6s);
  EXPECT_EQ(clock.now(), 7s);
  clock.advance(1ms);
  EXPECT_EQ(clock.now(), 7001ms);
}

TEST(PacedClock, RunsAtItsSpeed) {
  PacedClock clock(50.0);
  const nanoseconds start = clock.now();
  clock.sleep_until(start + 1s);  // 20 ms of real time
  const nanoseconds elapsed = clock.now() - start;
  EXPECT_GE(elapsed, 1s);
  EXPECT_LT(elapsed, 10s) << "a loaded machine may be late, but not by 180 ms of real time";
  EXPECT_THROW(PacedClock(0.0), std::invalid_argument);
}

TEST(MemoryOutputBank, RecordsWritesAndForceSafe) {
  ManualClock clock;
  MemoryOutputBank bank(3, 0b100, clock);
  EXPECT_EQ(bank.mask(), 0b100U) << "starts at the safe value";
  clock.advance(1ms);
  bank.write(0xFF);
  EXPECT_EQ(bank.mask(), 0b111U) << "only the bank's lines";
  bank.force_safe();
  EXPECT_EQ(bank.mask(), 0b100U);
  ASSERT_EQ(bank.history().size(), 1U);
  EXPECT_EQ(bank.history()[0].time, 1ms);
  EXPECT_THROW(MemoryOutputBank(33, 0, clock), std::invalid_argument);
}

TEST(ManualDigitalInput, ReportsChangesWithTheirTime) {
  ManualClock clock;
  ManualDigitalInput key(clock);
  EXPECT_FALSE(key.sample().active);
  clock.advance(2s);
  key.set(true);
  key.set(true);  // no change
  const DigitalInputSample s = key.sample();
  EXPECT_TRUE(s.active);
  EXPECT_EQ(s.time, 2s);
  EXPECT_EQ(s.change_count, 1U);
}

TEST(Debouncer, AcceptsALevelOnlyAfterItHolds) {
  Debouncer d(30ms);
  EXPECT_FALSE(d.feed(true, 0ms));
  EXPECT_FALSE(d.feed(false, 10ms));  // bounce
  EXPECT_FALSE(d.feed(true, 15ms));
  EXPECT_TRUE(d.pending());
  EXPECT_EQ(d.pending_until(), 45ms);
  EXPECT_FALSE(d.settle(44ms));
  EXPECT_TRUE(d.settle(45ms));
  EXPECT_TRUE(d.level());
  EXPECT_EQ(d.changed_at(), 45ms);
  EXPECT_FALSE(d.feed(false, 50ms));
  EXPECT_TRUE(d.feed(false, 90ms));
  EXPECT_FALSE(d.level());
}

}  // namespace
}  // namespace weedspray::io::sim
