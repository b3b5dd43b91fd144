// SPDX-License-Identifier: Apache-2.0
// Placement in distance coordinates, closed loop on the simulated machine
// (placement_harness.hpp): with the speed varying 0.5-2.5 m/s, each zone's spray must start
// and stop within 5 cm of the ground interval its frame imaged.
#include <gtest/gtest.h>

#include "tests/sim/daemon/placement_harness.hpp"

namespace weedspray::daemon {
namespace {

TEST(Placement, SprayStartsAndStopsWithin5cmOfTheImagedGround) {
  const PlacementFigures figures = run_placement(placement_config());
  EXPECT_LE(figures.max_cm, 5.0);
}

}  // namespace
}  // namespace weedspray::daemon
