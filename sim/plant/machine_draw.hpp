// SPDX-License-Identifier: Apache-2.0
// Realistic machines drawn from documented spreads around realistic_plant_params(): what the
// lab's --plants experiments run, and what `weedsprayd --sim` runs unless told to use the ideal
// bench. Pure and deterministic for (seed, index).
//
// Spreads (each: source, or "invented" with the range swept):
//   pump open flow            x U(0.9, 1.1)      24 V diaphragm pump class 5-8 L/min (spread
//                                                 between units of one model: invented)
//   pump shut-off pressure    x U(0.9, 1.1)      invented
//   pump rated speed          U(1500, 2500) rpm  invented (class 1500-3000 rpm)
//   pump load speed sag       U(0.1, 0.3)        invented (PM motor droop at stall)
//   supply voltage as made    U(23, 27) V        24 V lead-acid system: 23-28.8 V charging
//   feed hose length          U(2, 5) m          inertance and friction scale with it
//   air chamber precharge     U(0.5, 0.9) x 0.2 MPa  dampers precharged 60-80 % (+-10 %)
//   nozzle k, valve delays    per nozzle, PlantParams spreads (ISO 5682, valve datasheets)
//   valve base delays         x U(0.8, 1.25)     invented (coil and spring between batches)
//   meter K error as made     U(-0.02, 0.02)     LWGY class +-1 % of reading, twice for wear
//   wheel slip                U(-0.03, 0.05)     invented (trailed / driven ground wheel)
//   pressure transmitter      offset U(-0.5, 0.5) % of span, span U(-1, 1) %, offset drift
//                             U(-0.1, 0.1) % of span per hour: 0.25-0.5 % FS class datasheets
//                             (drift invented); the controller converts by the label
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "sim/plant/hydraulic_plant.hpp"

namespace weedspray::sim::plant {

struct Machine {
  PlantParams params{};
  std::uint64_t seed = 1;  // the plant's own seed (nozzle spread, valve delays, noise)
};

// Machine `index` of the fleet `seed`. Different (seed, index) pairs give independent machines.
Machine draw_machine(std::uint64_t seed, int index);
// Machines first_index .. first_index + count - 1 of the fleet `seed`.
std::vector<Machine> draw_machines(std::uint64_t seed, int count, int first_index = 0);

// The random stream `stream` of machine `index` of the fleet `seed`: draw_machine() takes
// stream 1; other draws about the same machine (what changes on it later) take their own
// stream, so adding one never moves the machines already drawn.
std::mt19937_64 machine_rng(std::uint64_t seed, int index, std::uint64_t stream);
// One draw from U(lo, hi) on a machine's stream.
double draw_uniform(std::mt19937_64& rng, double lo, double hi);

}  // namespace weedspray::sim::plant
