// SPDX-License-Identifier: Apache-2.0
// The map export: the as-applied CSV files of one log folder, or of several (one per board of a
// machine), -> one map's sprayed-stretch and weed-density layers (ogr_map_writer.hpp). Streams:
// one row in memory at a time, stretches written as they close; only the grid's cell sums are
// held to the end. A client-side job (weedspray-export-map), never part of the daemon.
//
// Each board's folder is read on its own, file by file: its stretches end with its files (a
// stretch never joins two boards' records, whose clocks and nozzles are their own), and its
// nozzles sit where its log placed them (each board's [gnss] offsets). The grid is one over all.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "daemon/maps/ogr_map_writer.hpp"

namespace weedspray::daemon::maps {

struct ExportOptions {
  // One folder: the map as of one board. Several: every stretch carries its board's name
  // (board_names) in the field `board`.
  std::vector<std::filesystem::path> log_dirs;
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
  std::vector<std::filesystem::path> dirs_without_position;  // no record with a position
};

// The boards' names for their log folders: each folder's name ("left"), or where two share it
// (".../left/as-applied", ".../right/as-applied"), as many of its last path components as tell
// them apart ("left/as-applied"). The log's header names no board. Throws std::runtime_error
// when a folder is given twice.
std::vector<std::string> board_names(const std::vector<std::filesystem::path>& dirs);

// Throws std::runtime_error naming the folder or file at fault (before writing anything when a
// folder is missing or holds no as-applied file).
ExportSummary export_map(const ExportOptions& options);

}  // namespace weedspray::daemon::maps
