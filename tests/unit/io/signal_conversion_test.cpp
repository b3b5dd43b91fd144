// SPDX-License-Identifier: Apache-2.0
#include "io/signal_conversion.hpp"

#include <gtest/gtest.h>

namespace weedspray::io {
namespace {

CurrentLoopSensorConfig sensor_0_to_1_mpa() {
  return {};
}  // 165 ohm, 4-20 mA = 0-1 MPa

TEST(SignalConversion, CurrentLoopEndsAndMiddle) {
  const auto c = sensor_0_to_1_mpa();
  // 4 mA * 165 ohm = 0.66 V; 20 mA = 3.3 V; 12 mA = 1.98 V.
  EXPECT_NEAR(pressure_from_sensor_volts(0.66, c).pressure_mpa, 0.0, 1e-9);
  EXPECT_NEAR(pressure_from_sensor_volts(3.3, c).pressure_mpa, 1.0, 1e-9);
  EXPECT_NEAR(pressure_from_sensor_volts(1.98, c).pressure_mpa, 0.5, 1e-9);
  EXPECT_NEAR(pressure_from_sensor_volts(1.98, c).current_ma, 12.0, 1e-9);
  EXPECT_TRUE(pressure_from_sensor_volts(1.98, c).ok());
}

TEST(SignalConversion, FaultRuleBrokenWireAndShort) {
  const auto c = sensor_0_to_1_mpa();
  EXPECT_EQ(pressure_from_sensor_volts(0.0, c).status, SensorStatus::kOpenCircuit);
  EXPECT_EQ(pressure_from_sensor_volts(volts_from_current_ma(3.59, c), c).status,
            SensorStatus::kOpenCircuit);
  EXPECT_EQ(pressure_from_sensor_volts(volts_from_current_ma(3.61, c), c).status,
            SensorStatus::kOk);
  EXPECT_EQ(pressure_from_sensor_volts(volts_from_current_ma(20.99, c), c).status,
            SensorStatus::kOk);
  EXPECT_EQ(pressure_from_sensor_volts(volts_from_current_ma(21.01, c), c).status,
            SensorStatus::kShortCircuit);
  EXPECT_FALSE(pressure_from_sensor_volts(volts_from_current_ma(24.0, c), c).ok());
}

TEST(SignalConversion, SensorVoltsRoundTrip) {
  CurrentLoopSensorConfig c;
  c.pressure_at_max_mpa = 1.6;
  c.shunt_ohms = 150.0;
  for (double p = 0.0; p <= 1.6; p += 0.1) {
    EXPECT_NEAR(pressure_from_sensor_volts(sensor_volts_from_pressure_mpa(p, c), c).pressure_mpa, p,
                1e-9);
  }
}

TEST(SignalConversion, ValveDriveDacToValveVolts) {
  const ValveDriveConfig d;  // 0-3.3 V DAC, x(10/3.3), 10 V full scale
  EXPECT_NEAR(valve_volts_from_dac_volts(3.3, d), 10.0, 1e-9);
  EXPECT_NEAR(valve_volts_from_dac_volts(1.65, d), 5.0, 1e-9);
  EXPECT_NEAR(valve_volts_from_dac_volts(5.0, d), 10.0, 1e-9) << "DAC range is clamped";
  EXPECT_NEAR(valve_volts_from_dac_volts(-1.0, d), 0.0, 1e-9);
  EXPECT_NEAR(valve_opening_from_dac_volts(1.65, d), 0.5, 1e-9);
  EXPECT_NEAR(dac_volts_from_valve_opening(0.25, d), 0.825, 1e-9);
  EXPECT_NEAR(dac_volts_from_valve_volts(10.0, d), 3.3, 1e-9);
  EXPECT_NEAR(dac_volts_from_valve_opening(2.0, d), 3.3, 1e-9);
}

// A reverse-acting return valve: fully open (the safe position) at 0 V, so a DAC that resets,
// browns out or loses its wire opens the relief path.
TEST(SignalConversion, AValveThatOpensAtZeroVoltsIsDrivenReversed) {
  ValveDriveConfig d;
  d.opens_at_zero_volts = true;
  EXPECT_NEAR(dac_volts_from_valve_opening(1.0, d), 0.0, 1e-9);
  EXPECT_NEAR(dac_volts_from_valve_opening(0.0, d), 3.3, 1e-9);
  EXPECT_NEAR(dac_volts_from_valve_opening(0.25, d), 2.475, 1e-9);
  EXPECT_NEAR(valve_opening_from_dac_volts(0.0, d), 1.0, 1e-9);
  EXPECT_NEAR(valve_opening_from_dac_volts(3.3, d), 0.0, 1e-9);
  for (double opening = 0.0; opening <= 1.0; opening += 0.1)
    EXPECT_NEAR(valve_opening_from_dac_volts(dac_volts_from_valve_opening(opening, d), d), opening,
                1e-9);
}

}  // namespace
}  // namespace weedspray::io
