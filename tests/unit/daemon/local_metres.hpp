// SPDX-License-Identifier: Apache-2.0
// North/east metres between two positions, for the map and as-applied tests' assertions.
#pragma once

#include <utility>

#include "daemon/records/map_geometry.hpp"

namespace weedspray::daemon::test {

inline std::pair<double, double> metres(LatLon origin, LatLon p) {
  double n = 0, e = 0;
  local_offset(origin, p, n, e);
  return {n, e};
}

}  // namespace weedspray::daemon::test
