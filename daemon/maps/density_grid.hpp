// SPDX-License-Identifier: Apache-2.0
// The weed-density grid: square cells of cell_m on the ground, each the mean weed and crop
// density of every nozzle patch that fell in it (sprayed or not). Cells are laid out in the
// local north/east plane of the first point (see map_geometry.hpp), so over a field they stay
// cell_m squares to well under a millimetre. Pure: points in, cells out.
#pragma once

#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "daemon/records/map_geometry.hpp"

namespace weedspray::daemon::maps {

struct DensityCell {
  std::array<LatLon, 4> corners;  // south-west, south-east, north-east, north-west
  double weed_density = 0;        // means over the samples
  double crop_density = 0;
  std::uint64_t samples = 0;
};

class DensityGrid {
 public:
  explicit DensityGrid(double cell_m) : cell_m_(cell_m) {}
  void add(LatLon where, double weed_density, double crop_density);
  // Every cell with a sample, in a fixed order (by row, then column).
  std::vector<DensityCell> cells() const;
  std::size_t size() const { return sums_.size(); }

 private:
  struct Sums {
    double weed = 0, crop = 0;
    std::uint64_t n = 0;
  };
  double cell_m_;
  bool has_origin_ = false;
  LatLon origin_;
  std::unordered_map<std::int64_t, Sums> sums_;  // key: (row << 32) | (column & 0xffffffff)
};

}  // namespace weedspray::daemon::maps
