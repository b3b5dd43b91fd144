// SPDX-License-Identifier: Apache-2.0
// The realism effects of the hydraulic plant, each against the law it documents.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sim/plant/hydraulic_plant.hpp"

namespace weedspray::sim::plant {
namespace {

PlantParams quiet(PlantParams p) {
  p.nozzle.k_spread_sigma = 0.0;
  p.boom.valve_k_spread_sigma = 0.0;
  p.pressure_sensor.noise_volts_sigma = 0.0;
  return p;
}

HydraulicPlant running(const PlantParams& p, std::uint32_t mask, double volts, double seconds) {
  HydraulicPlant plant(p, 3);
  plant.set_pump(true);
  plant.set_valves(mask);
  plant.set_return_valve_volts(volts);
  plant.step(seconds);
  return plant;
}

TEST(PlantRealism, ClosingValvesOnAMovingColumnSpikesTheBoomPressure) {
  // With the hose's inertance the flow still arriving after the valves shut compresses the
  // boom: a spike above the steady pressure (Joukowsky rho a dv ~ 0.12 MPa for this hose).
  // One pressure node (the ideal bench) has no such spike.
  auto spike = [](const PlantParams& p) {
    HydraulicPlant plant = running(p, 0xF, 4.0, 6.0);
    const double steady = plant.boom_pressure_mpa();
    plant.set_valves(0x0);
    double peak = 0.0;
    for (int k = 0; k < 400; ++k) {
      plant.step(1e-4);
      peak = std::max(peak, plant.boom_pressure_mpa());
    }
    return peak - steady;
  };
  const double with_inertia = spike(quiet(realistic_plant_params()));
  PlantParams ideal = quiet(realistic_plant_params());
  ideal.boom.inertance_mpa_s2_per_l = 0.0;
  const double without = spike(ideal);
  EXPECT_GT(with_inertia, 0.05);
  EXPECT_LT(without, 0.01);
}

TEST(PlantRealism, ThreeChamberPumpRipplesSixTimesARevolution) {
  PlantParams p = quiet(realistic_plant_params());
  HydraulicPlant plant = running(p, 0xF, 4.0, 5.0);
  const double rpm = plant.pump_rpm();
  ASSERT_GT(rpm, 1000.0);
  // Count the rising crossings of the mean flow over one second, and the ripple depth.
  double lo = 1e9, hi = 0.0, mean = 0.0;
  const int samples = 10000;
  std::vector<double> q(samples);
  for (int k = 0; k < samples; ++k) {
    plant.step(1e-4);
    q[static_cast<std::size_t>(k)] = plant.pump_flow_l_per_min();
    mean += q[static_cast<std::size_t>(k)] / samples;
  }
  int crossings = 0;
  for (int k = 1; k < samples; ++k) {
    lo = std::min(lo, q[static_cast<std::size_t>(k)]);
    hi = std::max(hi, q[static_cast<std::size_t>(k)]);
    crossings +=
        q[static_cast<std::size_t>(k - 1)] < mean && q[static_cast<std::size_t>(k)] >= mean;
  }
  // The three discharge strokes overlap: the summed flow ripples 2 x 3 times a revolution.
  EXPECT_NEAR(crossings, 6.0 * rpm / 60.0, 6.0 * rpm / 60.0 * 0.1);
  // Sum of three half-sines: from 0.907 to 1.047 of the mean.
  EXPECT_NEAR(lo / mean, 0.907, 0.02);
  EXPECT_NEAR(hi / mean, 1.047, 0.02);
}

TEST(PlantRealism, PumpSpeedSagsWithLoadAndFollowsTheSupplyVoltage) {
  PlantParams p = quiet(realistic_plant_params());
  HydraulicPlant low = running(p, 0xF, 10.0, 5.0);  // return open: low pressure
  HydraulicPlant high = running(p, 0x1, 0.0, 5.0);  // one nozzle, return shut: high pressure
  ASSERT_GT(high.line_pressure_mpa(), low.line_pressure_mpa() + 0.3);
  EXPECT_LT(high.pump_rpm(), low.pump_rpm());
  HydraulicPlant sagged = running(p, 0xF, 10.0, 5.0);
  sagged.set_supply_volts(21.6);  // 24 V battery under load
  sagged.step(3.0);
  EXPECT_NEAR(sagged.pump_rpm() / low.pump_rpm(), 0.9, 0.02);
  // Mean flow over whole pulsation cycles (the instantaneous flow ripples +-7 %).
  auto mean_flow = [](HydraulicPlant& plant) {
    double q = 0.0;
    for (int k = 0; k < 2000; ++k) {
      plant.step(1e-4);
      q += plant.pump_flow_l_per_min() / 2000.0;
    }
    return q;
  };
  EXPECT_LT(mean_flow(sagged), mean_flow(low) * 0.95);
}

TEST(PlantRealism, ValveAndBoomSectionsCostFlowAlongTheBoom) {
  PlantParams p = quiet(realistic_plant_params());
  HydraulicPlant plant = running(p, 0xF, 4.0, 6.0);
  const double boom = plant.boom_pressure_mpa();
  // Nozzle 1 sits at the feed: nozzle and valve in series at the boom pressure.
  const double kn = plant.nozzle_truth(0).k_l_per_min_sqrt_mpa;
  const double kv = plant.nozzle_truth(0).valve_k_l_per_min_sqrt_mpa;
  ASSERT_GT(kv, 0.0);
  const double series = kn * kv / std::sqrt(kn * kn + kv * kv);
  EXPECT_NEAR(plant.nozzle_flow_l_per_min(0), series * std::sqrt(boom), 1e-3);
  EXPECT_LT(plant.nozzle_flow_l_per_min(0), kn * std::sqrt(boom) * 0.99);
  // Each further tap loses the section drops before it.
  for (int i = 1; i < plant.nozzle_count(); ++i)
    EXPECT_LT(plant.nozzle_flow_l_per_min(i), plant.nozzle_flow_l_per_min(i - 1));
}

TEST(PlantRealism, FlowMeterUnderReadsAtLowFlow) {
  auto pulses_per_litre = [](std::uint32_t mask, double volts) {
    PlantParams p = quiet(realistic_plant_params());
    HydraulicPlant plant = running(p, mask, volts, 2.0);
    const auto p0 = plant.flow_meter_pulses();
    const double v0 = plant.total_delivered_l();
    plant.step(30.0);
    return static_cast<double>(plant.flow_meter_pulses() - p0) / (plant.total_delivered_l() - v0) /
           plant.true_meter_pulses_per_l();
  };
  const double one_nozzle = pulses_per_litre(0x1, 10.0);  // ~0.5 L/min
  const double four = pulses_per_litre(0xF, 4.0);         // ~2.7 L/min
  EXPECT_LT(one_nozzle, 0.98);
  EXPECT_GT(four, 0.995);
  EXPECT_LT(four, 1.005);
}

TEST(PlantRealism, WheelSlipsAndValvesAgeAndDrift) {
  PlantParams p = quiet(realistic_plant_params());
  HydraulicPlant plant(p, 1);
  plant.set_ground_speed(1.0);
  plant.set_wheel_slip(0.05);
  plant.step(10.0);
  EXPECT_NEAR(static_cast<double>(plant.wheel_pulses()), 10.0 * 1.05 * 20.0, 1.0);
  // An aged valve opens later than its drawn delay.
  HydraulicPlant aged(p, 1);
  aged.set_valve_ageing(0, 1.3);
  const double delay = aged.nozzle_truth(0).open_delay_s;
  aged.set_valves(0x1);
  aged.step(delay * 1.2);
  EXPECT_EQ(aged.valve_opening(0), 0.0);
  aged.step(delay * 0.1 + aged.nozzle_truth(0).open_travel_s * 1.3 + 1e-3);
  EXPECT_EQ(aged.valve_opening(0), 1.0);
  // Each valve's delays drift at its own drawn rate; the rates differ between valves.
  EXPECT_NE(plant.nozzle_truth(0).delay_drift_per_hour, plant.nozzle_truth(1).delay_drift_per_hour);
}

TEST(PlantRealism, IdealBenchKeepsItsDrawsWhenRealismIsAdded) {
  // The realism effects draw from their own stream: the ideal bench's nozzles are the same.
  HydraulicPlant ideal(PlantParams{}, 9);
  PlantParams p = PlantParams{};
  p.boom.valve_k_l_per_min_sqrt_mpa = 7.9;
  p.boom.valve_k_spread_sigma = 0.1;
  HydraulicPlant real(p, 9);
  for (int i = 0; i < ideal.nozzle_count(); ++i) {
    EXPECT_EQ(ideal.nozzle_truth(i).k_l_per_min_sqrt_mpa,
              real.nozzle_truth(i).k_l_per_min_sqrt_mpa);
    EXPECT_EQ(ideal.nozzle_truth(i).open_delay_s, real.nozzle_truth(i).open_delay_s);
  }
}

}  // namespace
}  // namespace weedspray::sim::plant
