// SPDX-License-Identifier: Apache-2.0
#include "lab/experiments/machines.hpp"
#include "lab/experiments/vocabulary.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace weedspray::lab::experiments {
namespace {

std::mt19937_64 machine_rng(std::uint64_t seed, int index, std::uint64_t stream) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(index), static_cast<std::uint32_t>(stream)};
  return std::mt19937_64(seq);
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

}  // namespace

Machine draw_machine(std::uint64_t seed, int index) {
  auto rng = machine_rng(seed, index, 1);
  Machine m;
  plant::PlantParams& p = m.params;
  p = plant::realistic_plant_params();
  p.pump.open_flow_l_per_min *= uniform(rng, 0.9, 1.1);
  p.pump.shutoff_pressure_mpa *= uniform(rng, 0.9, 1.1);
  p.pump.rated_rpm = uniform(rng, 1500.0, 2500.0);
  p.pump.load_speed_sag = uniform(rng, 0.1, 0.3);
  p.pump.supply_volts = uniform(rng, 23.0, 27.0);
  const double hose = uniform(rng, 2.0, 5.0) / 3.0;  // relative to the 3 m default
  p.boom.inertance_mpa_s2_per_l *= hose;
  p.boom.friction_mpa_per_l_per_s_sq *= hose;
  p.line.air_chamber_precharge_mpa = 0.2 * uniform(rng, 0.5, 0.9);
  const double delays = uniform(rng, 0.8, 1.25);
  p.nozzle.open_delay_s *= delays;
  p.nozzle.close_delay_s *= delays;
  p.flow_meter.k_factor_error = uniform(rng, -0.02, 0.02);
  p.wheel.slip = uniform(rng, -0.03, 0.05);
  m.seed = rng();
  // The pressure transmitter's own error, from a stream of its own (the draws above stay).
  auto sensor_rng = machine_rng(seed, index, 3);
  p.pressure_sensor.offset_fraction = uniform(sensor_rng, -0.005, 0.005);
  p.pressure_sensor.span_error = uniform(sensor_rng, -0.01, 0.01);
  p.pressure_sensor.drift_per_hour = uniform(sensor_rng, -0.001, 0.001);
  return m;
}

std::vector<Machine> draw_machines(std::uint64_t seed, int count, int first_index) {
  std::vector<Machine> machines;
  for (int i = 0; i < count; ++i) machines.push_back(draw_machine(seed, first_index + i));
  return machines;
}

MachineChange draw_change(const Machine& machine, std::uint64_t seed, int index) {
  auto rng = machine_rng(seed, index, 2);
  MachineChange c;
  const int n = machine.params.nozzle_count;
  for (int i = 0; i < n; ++i) {
    c.nozzle_wear[static_cast<std::size_t>(i)] = uniform(rng, 0.0, 0.04);
    c.valve_ageing[static_cast<std::size_t>(i)] = uniform(rng, 1.0, 1.3);
  }
  c.blocked_nozzle = std::uniform_int_distribution<int>(0, n - 1)(rng);
  c.blockage = uniform(rng, 0.0, 0.05);
  c.meter_drift = uniform(rng, -0.01, 0.01);
  c.supply_volts_start = machine.params.pump.supply_volts;
  c.supply_volts_end = c.supply_volts_start + uniform(rng, -1.5, 0.5);
  c.speed_start_m_per_s = uniform(rng, 0.8, 1.2);
  c.speed_end_m_per_s = uniform(rng, 0.8, 1.2);
  return c;
}

MachineChange no_change(const Machine& machine) {
  MachineChange c;
  c.valve_ageing.fill(1.0);
  c.supply_volts_start = c.supply_volts_end = machine.params.pump.supply_volts;
  return c;
}

MachineChange draw_change_parts(const Machine& machine, std::uint64_t seed, int index,
                                ChangeParts parts) {
  const MachineChange drawn = draw_change(machine, seed, index);
  MachineChange kept = no_change(machine);
  if (parts == ChangeParts::kAll || parts == ChangeParts::kPerNozzle) {
    kept.nozzle_wear = drawn.nozzle_wear;
    kept.valve_ageing = drawn.valve_ageing;
    kept.blocked_nozzle = drawn.blocked_nozzle;
    kept.blockage = drawn.blockage;
  }
  if (parts == ChangeParts::kAll || parts == ChangeParts::kCommon) {
    kept.meter_drift = drawn.meter_drift;
    kept.supply_volts_end = drawn.supply_volts_end;
    kept.speed_start_m_per_s = drawn.speed_start_m_per_s;
    kept.speed_end_m_per_s = drawn.speed_end_m_per_s;
  }
  return kept;
}

void apply_change(plant::HydraulicPlant& plant, const MachineChange& change) {
  for (int i = 0; i < plant.nozzle_count(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    plant.set_nozzle_wear(i, change.nozzle_wear[k]);
    plant.set_valve_ageing(i, change.valve_ageing[k]);
  }
  if (change.blocked_nozzle >= 0 && change.blocked_nozzle < plant.nozzle_count())
    plant.set_nozzle_blockage(change.blocked_nozzle, change.blockage);
  plant.set_meter_drift(change.meter_drift);
  apply_change_progress(plant, change, 0.0);
}

void apply_change_progress(plant::HydraulicPlant& plant, const MachineChange& change,
                           double fraction) {
  const double f = std::clamp(fraction, 0.0, 1.0);
  plant.set_supply_volts(change.supply_volts_start +
                         f * (change.supply_volts_end - change.supply_volts_start));
  plant.set_ground_speed(change.speed_start_m_per_s +
                         f * (change.speed_end_m_per_s - change.speed_start_m_per_s));
}

Spread spread_of(std::span<const double> values, bool worst_is_min) {
  Spread s;
  s.count = static_cast<int>(values.size());
  if (values.empty()) return s;
  for (double v : values) s.mean += v / static_cast<double>(values.size());
  double ss = 0.0;
  for (double v : values) ss += (v - s.mean) * (v - s.mean);
  s.sd = values.size() > 1 ? std::sqrt(ss / static_cast<double>(values.size() - 1)) : 0.0;
  s.worst = worst_is_min ? *std::min_element(values.begin(), values.end())
                         : *std::max_element(values.begin(), values.end());
  return s;
}

}  // namespace weedspray::lab::experiments
