// SPDX-License-Identifier: Apache-2.0
#include "sim/plant/machine_draw.hpp"

namespace weedspray::sim::plant {

std::mt19937_64 machine_rng(std::uint64_t seed, int index, std::uint64_t stream) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(index), static_cast<std::uint32_t>(stream)};
  return std::mt19937_64(seq);
}

double draw_uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

Machine draw_machine(std::uint64_t seed, int index) {
  auto rng = machine_rng(seed, index, 1);
  Machine m;
  PlantParams& p = m.params;
  p = realistic_plant_params();
  p.pump.open_flow_l_per_min *= draw_uniform(rng, 0.9, 1.1);
  p.pump.shutoff_pressure_mpa *= draw_uniform(rng, 0.9, 1.1);
  p.pump.rated_rpm = draw_uniform(rng, 1500.0, 2500.0);
  p.pump.load_speed_sag = draw_uniform(rng, 0.1, 0.3);
  p.pump.supply_volts = draw_uniform(rng, 23.0, 27.0);
  const double hose = draw_uniform(rng, 2.0, 5.0) / 3.0;  // relative to the 3 m default
  p.boom.inertance_mpa_s2_per_l *= hose;
  p.boom.friction_mpa_per_l_per_s_sq *= hose;
  p.line.air_chamber_precharge_mpa = 0.2 * draw_uniform(rng, 0.5, 0.9);
  const double delays = draw_uniform(rng, 0.8, 1.25);
  p.nozzle.open_delay_s *= delays;
  p.nozzle.close_delay_s *= delays;
  p.flow_meter.k_factor_error = draw_uniform(rng, -0.02, 0.02);
  p.wheel.slip = draw_uniform(rng, -0.03, 0.05);
  m.seed = rng();
  // The pressure transmitter's own error, from a stream of its own (the draws above stay).
  auto sensor_rng = machine_rng(seed, index, 3);
  p.pressure_sensor.offset_fraction = draw_uniform(sensor_rng, -0.005, 0.005);
  p.pressure_sensor.span_error = draw_uniform(sensor_rng, -0.01, 0.01);
  p.pressure_sensor.drift_per_hour = draw_uniform(sensor_rng, -0.001, 0.001);
  return m;
}

std::vector<Machine> draw_machines(std::uint64_t seed, int count, int first_index) {
  std::vector<Machine> machines;
  for (int i = 0; i < count; ++i) machines.push_back(draw_machine(seed, first_index + i));
  return machines;
}

}  // namespace weedspray::sim::plant
