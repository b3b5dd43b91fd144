// SPDX-License-Identifier: Apache-2.0
// Machine variation for the --plants experiments: N sprayers drawn from documented spreads
// around realistic_plant_params(), and the change each one goes through between its calibration
// and the test (wear, a partial blockage, valve ageing, meter drift, supply voltage and ground
// speed changing during the run). Pure and deterministic for (seed, index).
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
// Changes after calibration:
//   nozzle wear               each x U(1.00, 1.04)  TeeJet wear tables: brass tips +10 % flow
//                                                   in ~50 h; invented share of a season
//   one nozzle blocked        U(0, 0.05)            invented (partial filter clogging)
//   valve ageing              each delay x U(1.0, 1.3)  invented
//   meter drift               U(-0.01, 0.01)        LWGY +-1 % of reading
//   supply voltage in the run ramps to U(-1.5, +0.5) V from as made  (battery load/charging)
//   ground speed in the run   ramps from U(0.8, 1.2) to U(0.8, 1.2) m/s
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "lab/experiments/vocabulary.hpp"
#include "sim/plant/hydraulic_plant.hpp"

namespace weedspray::lab::experiments {

struct Machine {
  plant::PlantParams params{};
  std::uint64_t seed = 1;  // the plant's own seed (nozzle spread, valve delays, noise)
};

struct MachineChange {
  std::array<double, plant::kMaxNozzles> nozzle_wear{};
  std::array<double, plant::kMaxNozzles> valve_ageing{};
  int blocked_nozzle = -1;
  double blockage = 0.0;
  double meter_drift = 0.0;
  double supply_volts_start = 24.0;
  double supply_volts_end = 24.0;
  double speed_start_m_per_s = 1.0;
  double speed_end_m_per_s = 1.0;
  bool operator==(const MachineChange&) const = default;
};

// Which parts of a drawn change a run gets: all of it, or one half to tell the halves' errors
// apart. Per-nozzle parts: each nozzle's wear, its valve's ageing, the partial blockage. Common
// parts: the meter's drift and the supply and speed ramps (one for the whole boom).
enum class ChangeParts { kAll, kCommon, kPerNozzle, kNone };

// Machine `index` of the fleet `seed`. Different (seed, index) pairs give independent machines.
Machine draw_machine(std::uint64_t seed, int index);
std::vector<Machine> draw_machines(std::uint64_t seed, int count, int first_index = 0);
// The change machine `index` goes through after its calibration.
MachineChange draw_change(const Machine& machine, std::uint64_t seed, int index);
// No change: the machine as it was calibrated.
MachineChange no_change(const Machine& machine);
// draw_change() with only `parts` of it kept (the others as made).
MachineChange draw_change_parts(const Machine& machine, std::uint64_t seed, int index,
                                ChangeParts parts);

// The static part of the change (wear, blockage, ageing, meter drift) and the start of the
// ramps; then apply_change_progress(fraction in [0, 1]) moves supply voltage and speed.
void apply_change(plant::HydraulicPlant& plant, const MachineChange& change);
void apply_change_progress(plant::HydraulicPlant& plant, const MachineChange& change,
                           double fraction);

// Mean, sample sd and worst of one figure over the machines.
struct Spread {
  double mean = 0.0;
  double sd = 0.0;
  double worst = 0.0;
  int count = 0;
};
// worst = the largest value (worst_is_min: the smallest).
Spread spread_of(std::span<const double> values, bool worst_is_min = false);

}  // namespace weedspray::lab::experiments
