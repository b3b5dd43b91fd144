// SPDX-License-Identifier: Apache-2.0
// Drawn machines: the same (seed, index) is the same machine, down to its nozzles' true flow
// coefficients, and other pairs are other machines, inside the documented spreads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "sim/plant/hydraulic_plant.hpp"
#include "sim/plant/machine_draw.hpp"

namespace weedspray::sim::plant {
namespace {

TEST(MachineDraw, DrawsAreReproducibleAndDiffer) {
  const Machine a = draw_machine(7, 0);
  EXPECT_EQ(a.params, draw_machine(7, 0).params);
  EXPECT_EQ(a.seed, draw_machine(7, 0).seed);
  EXPECT_FALSE(a.params == draw_machine(7, 1).params);
  EXPECT_FALSE(a.params == draw_machine(8, 0).params);
  EXPECT_NE(a.seed, draw_machine(8, 0).seed);
  // Drawn inside the documented spreads, on the realistic plant.
  for (const Machine& m : draw_machines(3, 10)) {
    EXPECT_GE(m.params.pump.rated_rpm, 1500.0);
    EXPECT_LE(m.params.pump.rated_rpm, 2500.0);
    EXPECT_LE(std::abs(m.params.flow_meter.k_factor_error), 0.02);
    EXPECT_GT(m.params.boom.inertance_mpa_s2_per_l, 0.0);
    EXPECT_EQ(m.params.pump.chambers, 3);
  }
}

TEST(MachineDraw, AFleetIsItsMachinesByIndex) {
  const auto fleet = draw_machines(5, 3, 10);
  ASSERT_EQ(fleet.size(), 3U);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(fleet[static_cast<std::size_t>(i)].params, draw_machine(5, 10 + i).params);
    EXPECT_EQ(fleet[static_cast<std::size_t>(i)].seed, draw_machine(5, 10 + i).seed);
  }
}

TEST(MachineDraw, TheSameSeedBuildsTheSameNozzlesAndAnotherSeedOthers) {
  const auto nozzle_ks = [](std::uint64_t seed) {
    const Machine m = draw_machine(seed, 0);
    const HydraulicPlant plant(m.params, m.seed);
    std::vector<double> ks;
    for (int i = 0; i < plant.nozzle_count(); ++i) {
      ks.push_back(plant.nozzle_truth(i).k_l_per_min_sqrt_mpa);
    }
    return ks;
  };
  EXPECT_EQ(nozzle_ks(1), nozzle_ks(1));
  EXPECT_NE(nozzle_ks(1), nozzle_ks(2));
}

TEST(MachineDraw, StreamsOfOneMachineAreIndependent) {
  auto one = machine_rng(1, 0, 1);
  auto two = machine_rng(1, 0, 2);
  EXPECT_NE(one(), two());
  auto again = machine_rng(1, 0, 1);
  auto first = machine_rng(1, 0, 1);
  EXPECT_EQ(draw_uniform(again, 0.0, 1.0), draw_uniform(first, 0.0, 1.0));
}

}  // namespace
}  // namespace weedspray::sim::plant
