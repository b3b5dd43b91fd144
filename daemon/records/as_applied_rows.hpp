// SPDX-License-Identifier: Apache-2.0
// Reads an as-applied CSV file record by record with every column the map export needs
// (as_applied_reader.hpp only sums volumes). Columns are found by name in the header, so later
// additions do not break it. Files written before the map columns existed read fine:
// has_map_columns() is false and no row has a position. A torn last line (power cut) is
// skipped and counted, as in as_applied_reader.hpp; a malformed line elsewhere is counted as
// damaged and skipped.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "daemon/records/map_geometry.hpp"

namespace weedspray::daemon {

struct AsAppliedRow {
  double time_s = 0;  // the daemon's monotonic clock
  double speed_m_per_s = 0;
  std::int64_t utc_ns = 0;  // 0: no UTC (no fix)
  bool has_position = false;
  LatLon antenna;
  bool nozzles_placed = false;  // each nozzle's patch position is known (a fix with a course)
  double course_deg = 0;
  double nozzle_width_m = 0;
  std::vector<double> duty_pct, density, crop_density, rate_l_per_ha, nozzle_speed_m_per_s;
  std::vector<LatLon> patch;  // nozzle patch centres (valid when nozzles_placed)
};

class AsAppliedRows {
 public:
  // Throws std::runtime_error naming the file when it cannot be read or its header is not an
  // as-applied header.
  explicit AsAppliedRows(const std::filesystem::path& file);

  bool has_map_columns() const { return map_columns_; }
  std::size_t nozzles() const { return nozzles_; }
  // The next complete record; false at the end of the file.
  bool next(AsAppliedRow& row);

  std::uint64_t torn_tail_lines() const { return torn_tail_lines_; }
  std::uint64_t damaged_lines() const { return damaged_lines_; }

 private:
  bool parse(AsAppliedRow& row);
  std::size_t column(std::string_view name) const;

  std::filesystem::path file_;
  std::ifstream in_;
  std::vector<std::string> header_;
  std::string line_;
  std::vector<std::string_view> fields_;
  std::size_t nozzles_ = 0;
  bool map_columns_ = false;
  std::size_t time_col_ = 0, speed_col_ = 0, duty_col_ = 0, density_col_ = 0, crop_col_ = 0;
  std::size_t utc_col_ = 0, lat_col_ = 0, lon_col_ = 0, course_col_ = 0, width_col_ = 0;
  std::size_t nozzle_lat_col_ = 0, nozzle_lon_col_ = 0, rate_col_ = 0, nozzle_speed_col_ = 0;
  std::uint64_t torn_tail_lines_ = 0;
  std::uint64_t damaged_lines_ = 0;
};

}  // namespace weedspray::daemon
