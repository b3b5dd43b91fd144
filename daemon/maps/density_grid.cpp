// SPDX-License-Identifier: Apache-2.0
#include "daemon/maps/density_grid.hpp"

#include <algorithm>
#include <cmath>

namespace weedspray::daemon::maps {
namespace {

std::int64_t key(std::int64_t row, std::int64_t column) {
  return static_cast<std::int64_t>(static_cast<std::uint64_t>(row) << 32 |
                                   (static_cast<std::uint64_t>(column) & 0xffffffffULL));
}

}  // namespace

void DensityGrid::add(LatLon where, double weed_density, double crop_density) {
  if (!has_origin_) {
    origin_ = where;
    has_origin_ = true;
  }
  double north = 0, east = 0;
  local_offset(origin_, where, north, east);
  const auto row = static_cast<std::int64_t>(std::floor(north / cell_m_));
  const auto column = static_cast<std::int64_t>(std::floor(east / cell_m_));
  Sums& s = sums_[key(row, column)];
  s.weed += weed_density;
  s.crop += crop_density;
  ++s.n;
}

std::vector<DensityCell> DensityGrid::cells() const {
  std::vector<std::pair<std::int64_t, Sums>> sorted(sums_.begin(), sums_.end());
  std::sort(sorted.begin(), sorted.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<DensityCell> out;
  out.reserve(sorted.size());
  for (const auto& [k, s] : sorted) {
    const double row = static_cast<double>(k >> 32);
    const double column = static_cast<double>(static_cast<std::int32_t>(k & 0xffffffff));
    DensityCell cell;
    const double n0 = row * cell_m_, e0 = column * cell_m_;
    cell.corners = {step(origin_, n0, e0), step(origin_, n0, e0 + cell_m_),
                    step(origin_, n0 + cell_m_, e0 + cell_m_), step(origin_, n0 + cell_m_, e0)};
    cell.weed_density = s.weed / static_cast<double>(s.n);
    cell.crop_density = s.crop / static_cast<double>(s.n);
    cell.samples = s.n;
    out.push_back(cell);
  }
  return out;
}

}  // namespace weedspray::daemon::maps
