// SPDX-License-Identifier: Apache-2.0
// The placement test's machinery: the whole runtime (cameras -> vision -> scheduler -> rate
// law -> PWM driver -> plant valves) run on the simulated machine, each zone's spray judged
// against the ground its frame really imaged, from the PLANT's true valve crossings and the
// true distance travelled when each frame was taken. Edges more than 5 cm off are test
// failures (gtest); the figures are returned and printed.
#pragma once

#include <cstddef>
#include <functional>

#include "daemon/backends/backends.hpp"
#include "daemon/config/config.hpp"
#include "daemon/sprayer/sprayer.hpp"

namespace weedspray::daemon {

struct PlacementFigures {
  std::size_t edges = 0;  // spray starts and stops judged
  double median_cm = 0;   // |error| over them
  double p95_cm = 0;
  double max_cm = 0;
};

// The run's settings: the speed swinging 0.5-2.5 m/s (a 16 s sine), a fully open valve for any
// zone past the decision threshold (so the distance scheduling is judged, not the duty
// cycle), the simulated valves' datasheet delays; PLACEMENT_PWM_HZ in the environment sets the
// PWM frequency.
Config placement_config();

// Called from the test's thread about every 0.5 ms of the 24 s run, after the plant moved:
// the sprayer, the backends and the seconds since the start.
using PlacementTick = std::function<void(Sprayer&, Backends&, double t)>;

PlacementFigures run_placement(const Config& config, const PlacementTick& tick = {});

}  // namespace weedspray::daemon
