// SPDX-License-Identifier: Apache-2.0
// Unit-level checks of the hydraulic plant model (label sim: they integrate seconds of
// simulated time).
#include "sim/plant/hydraulic_plant.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>

namespace weedspray::sim::plant {
namespace {

// Run the pump with all valves in `mask` and the return valve at `volts` until steady.
HydraulicPlant settled(std::uint32_t mask, double volts, std::uint64_t seed = 7) {
  HydraulicPlant plant(PlantParams{}, seed);
  plant.set_pump(true);
  plant.set_valves(mask);
  plant.set_return_valve_volts(volts);
  plant.step(8.0);
  return plant;
}

TEST(HydraulicPlant, NozzleFlowFollowsOrificeLaw) {
  HydraulicPlant plant = settled(0xF, 4.0);
  const double p = plant.line_pressure_mpa();
  ASSERT_GT(p, 0.1);
  for (int i = 0; i < plant.nozzle_count(); ++i) {
    const double k = plant.nozzle_truth(i).k_l_per_min_sqrt_mpa;
    EXPECT_NEAR(plant.nozzle_flow_l_per_min(i), k * std::sqrt(p), 1e-6);
  }
}

TEST(HydraulicPlant, DefaultNozzleGivesAboutTwoThirdsLitrePerMinuteAtPointTwoMpa) {
  HydraulicPlant plant(PlantParams{}, 1);
  for (int i = 0; i < plant.nozzle_count(); ++i) {
    const double q = plant.nozzle_full_open_flow_l_per_min(i, 0.2);
    EXPECT_GT(q, 0.58);
    EXPECT_LT(q, 0.72);
  }
}

TEST(HydraulicPlant, PressureRisesWhenReturnValveCloses) {
  const double open = settled(0xF, 10.0).line_pressure_mpa();
  const double half = settled(0xF, 5.0).line_pressure_mpa();
  const double closed = settled(0xF, 0.0).line_pressure_mpa();
  EXPECT_LT(open, half);
  EXPECT_LT(half, closed);
  // The controllable range must span the papers' set-points 0.2 and 0.4 MPa.
  EXPECT_LT(open, 0.2);
  EXPECT_GT(closed, 0.4);
}

TEST(HydraulicPlant, VolumeBalanceHoldsInSteadyState) {
  HydraulicPlant plant = settled(0x5, 3.0);
  EXPECT_NEAR(plant.pump_flow_l_per_min(),
              plant.return_flow_l_per_min() + plant.total_nozzle_flow_l_per_min(), 1e-3);
}

TEST(HydraulicPlant, FlowMeterCountsTruePulsesPerLitre) {
  HydraulicPlant plant = settled(0xF, 4.0);
  const double litres = plant.total_delivered_l();
  ASSERT_GT(litres, 0.05);
  const double per_litre = static_cast<double>(plant.flow_meter_pulses()) / litres;
  EXPECT_NEAR(per_litre, plant.true_meter_pulses_per_l(), 1.0 / litres + 1e-6);
  // The meter is not perfect: its true K-factor differs from the 8500 on the label.
  EXPECT_NEAR(plant.true_meter_pulses_per_l() / 8500.0 - 1.0,
              PlantParams{}.flow_meter.k_factor_error, 1e-12);
}

TEST(HydraulicPlant, SensorMapsPressureToFourToTwentyMilliamps) {
  PlantParams params;
  params.pressure_sensor.noise_volts_sigma = 0.0;
  HydraulicPlant plant(params, 3);
  EXPECT_NEAR(plant.sensor_current_ma(), 4.0, 1e-9);
  plant.set_pump(true);
  plant.set_valves(0xF);
  plant.set_return_valve_volts(4.0);
  plant.step(3.0);
  const double expected_ma = 4.0 + 16.0 * plant.line_pressure_mpa();
  EXPECT_NEAR(plant.sensor_current_ma(), expected_ma, 1e-3);
  EXPECT_NEAR(plant.pressure_sensor_volts(), expected_ma * 0.165, 1e-3);
  plant.set_sensor_wire_broken(true);
  EXPECT_LT(plant.sensor_current_ma(), 3.6);  // SPEC §4: below 3.6 mA is a fault
  plant.set_sensor_wire_broken(false);
  plant.set_sensor_shorted(true);
  EXPECT_GT(plant.sensor_current_ma(), 21.0);
}

// A transmitter off its label: its zero offset (a share of the 16 mA span, drifting with the
// plant's time) and span error move the current the controller converts by the label.
TEST(HydraulicPlant, SensorCarriesItsOffsetSpanErrorAndDrift) {
  PlantParams params;
  params.pressure_sensor.noise_volts_sigma = 0.0;
  params.pressure_sensor.offset_fraction = 0.005;
  params.pressure_sensor.span_error = -0.01;
  params.pressure_sensor.drift_per_hour = 0.36;  // fast, to see it in 10 s
  HydraulicPlant plant(params, 3);
  EXPECT_NEAR(plant.sensor_current_ma(), 4.0 + 16.0 * 0.005, 1e-9);  // no pressure: the offset
  plant.set_pump(true);
  plant.set_valves(0xF);
  plant.set_return_valve_volts(4.0);
  plant.step(10.0);  // the offset drifted by 0.1 % of span
  const double reading = 0.99 * plant.line_pressure_mpa() / params.pressure_sensor.full_scale_mpa;
  EXPECT_NEAR(plant.sensor_current_ma(), 4.0 + 16.0 * (0.006 + reading), 1e-3);
}

TEST(HydraulicPlant, WheelPulsesFollowDistance) {
  HydraulicPlant plant(PlantParams{}, 1);
  plant.set_ground_speed(1.5);
  plant.step(10.0);
  EXPECT_NEAR(plant.distance_m(), 15.0, 1e-6);
  EXPECT_NEAR(static_cast<double>(plant.wheel_pulses()), 15.0 * 20.0, 1.0);
}

TEST(HydraulicPlant, ValveOpensAfterItsDelayAndClosesLater) {
  HydraulicPlant plant = settled(0x0, 4.0);
  const NozzleTruth& truth = plant.nozzle_truth(0);
  plant.set_valves(0x1);
  plant.step(truth.open_delay_s * 0.9);
  EXPECT_EQ(plant.valve_opening(0), 0.0);
  plant.step(truth.open_delay_s * 0.1 + PlantParams{}.nozzle.open_travel_s + 1e-4);
  EXPECT_EQ(plant.valve_opening(0), 1.0);
  plant.set_valves(0x0);
  plant.step(truth.close_delay_s * 0.9);
  EXPECT_EQ(plant.valve_opening(0), 1.0);
  plant.step(truth.close_delay_s * 0.1 + PlantParams{}.nozzle.close_travel_s + 1e-4);
  EXPECT_EQ(plant.valve_opening(0), 0.0);
}

// Valves closed over and over, each time with another spool speed (ageing) and advanced in
// random step lengths as the daemon's loops drive the simulated machine, come to rest exactly
// closed every time. A closing ramp that ends on its target by arithmetic (from - rate x time)
// can leave a residue that shrinks to a subnormal number no step moves any more: the spool
// then never quite closes (about one closing in a thousand).
TEST(HydraulicPlant, EveryClosingEndsExactlyClosed) {
  HydraulicPlant plant(PlantParams{}, 11);
  plant.set_pump(true);
  std::mt19937 random(5);
  std::uniform_real_distribution<double> step_s(0.0001, 0.003);
  std::uniform_real_distribution<double> ageing(0.8, 2.5);
  const auto run_for = [&](double seconds) {
    for (double t = 0.0; t < seconds;) {
      const double dt = step_s(random);
      plant.step(dt);
      t += dt;
    }
  };
  const int nozzles = plant.nozzle_count();
  int left_open = 0;
  for (int closing = 0; closing < 500; ++closing) {
    for (int i = 0; i < nozzles; ++i) plant.set_valve_ageing(i, ageing(random));
    plant.set_valves((1U << nozzles) - 1U);
    run_for(0.08);
    plant.set_valves(0x0);
    run_for(0.1);
    for (int i = 0; i < nozzles; ++i) left_open += plant.valve_opening(i) != 0.0;
  }
  EXPECT_EQ(left_open, 0) << "valves left a little open of " << 500 * nozzles << " closings";
}

// A valve stuck open (sim fault): open and metered while every valve is commanded closed,
// closed again once freed.
TEST(HydraulicPlant, AStuckOpenValveFlowsWhateverItIsCommanded) {
  HydraulicPlant plant = settled(0x0, 4.0);
  const std::uint64_t pulses_closed = plant.flow_meter_pulses();
  plant.step(1.0);
  EXPECT_EQ(plant.flow_meter_pulses(), pulses_closed) << "no flow with every valve closed";
  plant.set_valve_stuck_open(2, true);
  plant.step(1.0);
  plant.set_valves(0x0);
  plant.step(1.0);
  EXPECT_EQ(plant.valve_opening(2), 1.0);
  EXPECT_EQ(plant.valve_opening(0), 0.0);
  EXPECT_GT(plant.nozzle_flow_l_per_min(2), 0.1);
  EXPECT_GT(plant.flow_meter_pulses(), pulses_closed + 100);
  plant.set_valve_stuck_open(2, false);
  plant.step(1.0);
  EXPECT_EQ(plant.valve_opening(2), 0.0);
}

TEST(HydraulicPlant, SameSeedReproducesExactlyAndOtherSeedDiffers) {
  auto run = [](std::uint64_t seed) {
    HydraulicPlant plant(PlantParams{}, seed);
    plant.set_pump(true);
    plant.set_return_valve_volts(4.0);
    for (int k = 0; k < 300; ++k) {
      plant.set_valves(static_cast<std::uint32_t>(k % 16));
      plant.step(0.01);
    }
    return std::make_pair(plant.total_delivered_l(), plant.pressure_sensor_volts());
  };
  EXPECT_EQ(run(11), run(11));
  EXPECT_NE(run(11).first, run(12).first);
}

TEST(HydraulicPlant, NozzlesDifferByAFewPercent) {
  HydraulicPlant plant(PlantParams{}, 5);
  double lo = 1e9, hi = 0;
  for (int i = 0; i < plant.nozzle_count(); ++i) {
    lo = std::min(lo, plant.nozzle_truth(i).k_l_per_min_sqrt_mpa);
    hi = std::max(hi, plant.nozzle_truth(i).k_l_per_min_sqrt_mpa);
  }
  EXPECT_GT(hi / lo - 1.0, 0.001);
  EXPECT_LT(hi / lo - 1.0, 0.11);
}

TEST(HydraulicPlant, EmptyTankStarvesThePump) {
  HydraulicPlant plant = settled(0xF, 4.0);
  plant.set_tank_level_l(0.0);
  plant.step(2.0);
  EXPECT_LT(plant.line_pressure_mpa(), 0.01);
}

TEST(HydraulicPlant, BlockedNozzleRaisesPressureAndStopsItsFlow) {
  HydraulicPlant plant = settled(0xF, 4.0);
  const double before = plant.line_pressure_mpa();
  plant.set_nozzle_blockage(2, 1.0);
  plant.step(3.0);
  EXPECT_GT(plant.line_pressure_mpa(), before + 0.01);
  EXPECT_EQ(plant.nozzle_flow_l_per_min(2), 0.0);
}

TEST(HydraulicPlant, RejectsBadParametersByName) {
  PlantParams params;
  params.nozzle_count = 0;
  try {
    HydraulicPlant plant(params, 1);
    FAIL() << "accepted nozzle_count = 0";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nozzle_count"), std::string::npos);
  }
  params = PlantParams{};
  params.integration_step_s = 0.01;
  EXPECT_THROW(HydraulicPlant(params, 1), std::invalid_argument);
}

}  // namespace
}  // namespace weedspray::sim::plant

namespace weedspray::sim::plant {
namespace {

TEST(HydraulicPlant, ValveReversedMidTravelCoastsOnThenReverses) {
  PlantParams params;
  params.nozzle.delay_spread_sigma = 0.0;
  HydraulicPlant plant(params, 3);
  plant.set_pump(true);
  plant.set_valves(0x1);
  // Open dead time, then half the travel.
  plant.step(params.nozzle.open_delay_s + 0.5 * params.nozzle.open_travel_s);
  const double halfway = plant.valve_opening(0);
  ASSERT_GT(halfway, 0.3);
  ASSERT_LT(halfway, 0.7);
  plant.set_valves(0x0);
  // During the closing dead time the spool keeps going the way it was going (not frozen).
  plant.step(0.5 * params.nozzle.open_travel_s);
  EXPECT_GT(plant.valve_opening(0), halfway + 0.3);
  plant.step(params.nozzle.close_delay_s);  // dead time over: it is closing now
  const double later = plant.valve_opening(0);
  plant.step(0.5 * params.nozzle.close_travel_s);
  EXPECT_LT(plant.valve_opening(0), later);
  plant.step(params.nozzle.close_travel_s);
  EXPECT_EQ(plant.valve_opening(0), 0.0);
}

TEST(HydraulicPlant, ValveCommandedBackWithinItsDeadTimeNeverMoves) {
  PlantParams params;
  params.nozzle.delay_spread_sigma = 0.0;
  HydraulicPlant plant(params, 3);
  plant.set_valves(0x1);
  plant.step(0.5 * params.nozzle.open_delay_s);
  plant.set_valves(0x0);
  for (int i = 0; i < 20; ++i) {
    plant.step(0.005);
    EXPECT_EQ(plant.valve_opening(0), 0.0);
  }
}

}  // namespace
}  // namespace weedspray::sim::plant
