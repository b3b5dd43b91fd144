// The map export: the as-applied CSV files of a log folder -> the sprayed-stretch and
// weed-density layers (ogr_map_writer.hpp). Streams: one row in memory at a time, stretches
// written as they close; only the grid's cell sums are held to the end. A client-side job
// (weedspray-export-map), never part of the daemon.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

#include "daemon/maps/ogr_map_writer.hpp"

namespace weedspray::daemon::maps {

struct ExportOptions {
  std::filesystem::path log_dir;
  std::filesystem::path out;
  MapFormat format = MapFormat::kGpkg;
  std::optional<std::int64_t> from_utc_ns, to_utc_ns;  // records in [from, to]
  double cell_m = 2.0;
  StretchOptions stretch;
  // Two records further apart than this (a restart, a stuck writer) do not join a stretch.
  double max_gap_s = 1.0;
  bool overwrite = false;
};

struct ExportSummary {
  std::size_t files = 0;
  std::size_t files_without_position = 0;  // written before the map columns existed: skipped
  std::uint64_t records = 0;               // in the window, read
  std::uint64_t records_with_position = 0;
  std::uint64_t torn_or_damaged_lines = 0;
  std::uint64_t stretches = 0;
  std::uint64_t cells = 0;
  double volume_l = 0;  // over the stretches
  double area_m2 = 0;
};

// Throws std::runtime_error naming the folder or file at fault.
ExportSummary export_map(const ExportOptions& options);

}  // namespace weedspray::daemon::maps
