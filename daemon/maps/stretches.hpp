// SPDX-License-Identifier: Apache-2.0
// Per-nozzle sprayed stretches from as-applied rows: consecutive records in which one nozzle
// sprayed become one polygon, the strip its patch swept (nozzle width wide, following the
// heading through turns). A stretch ends when the nozzle closes, its position is lost, the
// caller ends every stretch (a gap in the log, the end of the time window), or the next record
// would take it past max_length_m, so a field map keeps detail along travel; the next stretch
// then starts where that one ended, without a gap. Pure: rows in, stretches out through a callback.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "daemon/records/as_applied_rows.hpp"
#include "daemon/records/map_geometry.hpp"

namespace weedspray::daemon::maps {

struct Stretch {
  std::size_t nozzle = 0;
  std::int64_t utc_start_ns = 0;  // 0: the log had no UTC (no fix time)
  std::int64_t utc_end_ns = 0;
  // The strip's left and right edges (looking forward) in travel order; the polygon is left
  // forward, then right backward.
  std::vector<LatLon> left, right;
  double volume_l = 0;  // rate x area, summed over the records
  double area_m2 = 0;   // ground speed x record time x nozzle width, summed
  double length_m = 0;
  double time_s = 0;
  // Sums over the records, each weighted by its time (means: divide by time_s).
  double duty_pct_s = 0, weed_density_s = 0, crop_density_s = 0, speed_m = 0;

  double rate_l_per_ha() const { return area_m2 > 0 ? volume_l / area_m2 * 10000.0 : 0; }
  double mean(double weighted_sum) const { return time_s > 0 ? weighted_sum / time_s : 0; }
};

struct StretchOptions {
  double max_length_m = 2.0;
};

class StretchBuilder {
 public:
  using Emit = std::function<void(const Stretch&)>;
  StretchBuilder(std::size_t nozzles, StretchOptions options, Emit emit);

  // One record, covering the `covers_s` seconds up to it (the time since the previous record).
  void add(const AsAppliedRow& row, double covers_s);
  // Ends every open stretch (a gap in the log, the end of the export's window or input).
  void end_all();

 private:
  void end(std::size_t nozzle);

  StretchOptions options_;
  Emit emit_;
  std::vector<Stretch> open_;
  std::vector<bool> is_open_;
};

}  // namespace weedspray::daemon::maps
