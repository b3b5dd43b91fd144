// SPDX-License-Identifier: Apache-2.0
#include "daemon/maps/stretches.hpp"

#include <cmath>
#include <numbers>

namespace weedspray::daemon::maps {
namespace {

// The points half a nozzle width left and right of a patch centre, across the heading.
void edges(LatLon centre, double heading_deg, double width_m, LatLon& left, LatLon& right) {
  const double h = heading_deg * std::numbers::pi / 180.0;
  // Right of the heading, (north, east) = (-sin h, cos h).
  const double rn = -std::sin(h) * width_m / 2;
  const double re = std::cos(h) * width_m / 2;
  left = step(centre, -rn, -re);
  right = step(centre, rn, re);
}

}  // namespace

StretchBuilder::StretchBuilder(std::size_t nozzles, StretchOptions options, Emit emit)
    : options_(options), emit_(std::move(emit)), open_(nozzles), is_open_(nozzles, false) {}

void StretchBuilder::end(std::size_t n) {
  if (!is_open_[n]) return;
  is_open_[n] = false;
  if (open_[n].left.size() >= 2) emit_(open_[n]);
}

void StretchBuilder::end_all() {
  for (std::size_t n = 0; n < open_.size(); ++n) end(n);
}

void StretchBuilder::add(const AsAppliedRow& row, double covers_s) {
  for (std::size_t n = 0; n < open_.size(); ++n) {
    const bool sprayed = row.nozzles_placed && n < row.duty_pct.size() && row.duty_pct[n] > 0;
    if (!sprayed) {
      end(n);
      continue;
    }
    Stretch& s = open_[n];
    const double speed = row.nozzle_speed_m_per_s[n];
    const double travel_m = std::max(speed, 0.0) * covers_s;
    const std::int64_t covers_ns = static_cast<std::int64_t>(covers_s * 1e9);
    LatLon left, right;
    // Would this record take it past max_length_m? Close it and go on from its last edge, so
    // the strip has no gap (1e-9: sums of equal steps land a hair off the limit).
    if (is_open_[n] && s.length_m > 0 && s.length_m + travel_m > options_.max_length_m + 1e-9) {
      const LatLon last_left = s.left.back();
      const LatLon last_right = s.right.back();
      const std::int64_t last_utc = s.utc_end_ns;
      end(n);
      s = Stretch{};
      s.left.push_back(last_left);
      s.right.push_back(last_right);
      s.utc_start_ns = last_utc;
      is_open_[n] = true;
    } else if (!is_open_[n]) {
      // A fresh start: the record's time covered the ground behind the patch.
      s = Stretch{};
      const double h = row.course_deg * std::numbers::pi / 180.0;
      const LatLon behind = step(row.patch[n], -travel_m * std::cos(h), -travel_m * std::sin(h));
      edges(behind, row.course_deg, row.nozzle_width_m, left, right);
      s.left.push_back(left);
      s.right.push_back(right);
      s.utc_start_ns = row.utc_ns != 0 ? row.utc_ns - covers_ns : 0;
      is_open_[n] = true;
    }
    s.nozzle = n;
    edges(row.patch[n], row.course_deg, row.nozzle_width_m, left, right);
    s.left.push_back(left);
    s.right.push_back(right);
    s.utc_end_ns = row.utc_ns;
    const double area = travel_m * row.nozzle_width_m;
    s.area_m2 += area;
    s.volume_l += row.rate_l_per_ha[n] * area / 10000.0;
    s.length_m += travel_m;
    s.time_s += covers_s;
    s.duty_pct_s += row.duty_pct[n] * covers_s;
    s.weed_density_s += row.density[n] * covers_s;
    s.crop_density_s += row.crop_density[n] * covers_s;
    s.speed_m += speed * covers_s;
  }
}

}  // namespace weedspray::daemon::maps
