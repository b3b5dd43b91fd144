// SPDX-License-Identifier: Apache-2.0
#include "lab/experiments/machines.hpp"
#include "lab/experiments/vocabulary.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace weedspray::lab::experiments {
MachineChange draw_change(const Machine& machine, std::uint64_t seed, int index) {
  auto rng = plant::machine_rng(seed, index, 2);
  MachineChange c;
  const int n = machine.params.nozzle_count;
  for (int i = 0; i < n; ++i) {
    c.nozzle_wear[static_cast<std::size_t>(i)] = plant::draw_uniform(rng, 0.0, 0.04);
    c.valve_ageing[static_cast<std::size_t>(i)] = plant::draw_uniform(rng, 1.0, 1.3);
  }
  c.blocked_nozzle = std::uniform_int_distribution<int>(0, n - 1)(rng);
  c.blockage = plant::draw_uniform(rng, 0.0, 0.05);
  c.meter_drift = plant::draw_uniform(rng, -0.01, 0.01);
  c.supply_volts_start = machine.params.pump.supply_volts;
  c.supply_volts_end = c.supply_volts_start + plant::draw_uniform(rng, -1.5, 0.5);
  c.speed_start_m_per_s = plant::draw_uniform(rng, 0.8, 1.2);
  c.speed_end_m_per_s = plant::draw_uniform(rng, 0.8, 1.2);
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
