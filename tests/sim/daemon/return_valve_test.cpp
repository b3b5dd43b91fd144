// SPDX-License-Identifier: Apache-2.0
// The return valve's safe direction ([dac] return_valve_open_at): with a reverse-acting valve
// (fully open at 0 V) the pressure loop still holds the set-point through the same DAC, and
// every safe write puts the DAC at 0 V; with the default valve it rests at full scale.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>

#include "daemon/backends/backends.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "io/sim/simulated_machine.hpp"
#include "tests/sim/daemon/run_until.hpp"
#include "tests/sim/daemon/spraying_machine.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

void holds_the_setpoint_and_rests_open(const std::string& open_at, double safe_volts) {
  SprayingMachine m(1.0);
  m.config.dac.return_valve_open_at = open_at;
  Options options;
  options.sim = true;
  m.backends = make_sim_backends(m.config, options);
  auto* dac = dynamic_cast<io::sim::SimulatedReturnValveDac*>(m.backends.return_valve);
  ASSERT_NE(dac, nullptr);
  m.start();
  Sprayer& sprayer = *m.sprayer;
  const double setpoint = m.config.pressure.setpoint_mpa;
  const auto at_setpoint = [&] {
    const PressureStatus p = sprayer.pressure();
    return p.pump_on && p.sensor_ok && std::abs(p.pressure_mpa - setpoint) < 0.03;
  };
  ASSERT_TRUE(run_until(m.backends, at_setpoint, 5s))
      << open_at << ": pressure " << sprayer.pressure().pressure_mpa << " MPa, set-point "
      << setpoint << ", DAC " << dac->last_volts() << " V";
  // Holding pressure means the valve is partly closed: the DAC is off its safe value.
  EXPECT_GT(std::abs(dac->last_volts() - safe_volts), 0.1) << open_at;
  sprayer.stop();
  EXPECT_NEAR(dac->last_volts(), safe_volts, 1e-9) << open_at << ": the stop's safe write";
  EXPECT_EQ(m.backends.return_valve->force_safe(), 0);
  EXPECT_NEAR(dac->last_volts(), safe_volts, 1e-9) << open_at;
}

TEST(ReturnValve, AValveOpenAtFullScaleRestsAtFullScale) {
  holds_the_setpoint_and_rests_open("full_scale", 3.3);
}

TEST(ReturnValve, AReverseActingValveHoldsTheSetpointAndRestsAtZeroVolts) {
  holds_the_setpoint_and_rests_open("zero", 0.0);
}

}  // namespace
}  // namespace weedspray::daemon
