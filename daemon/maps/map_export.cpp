#include "daemon/maps/map_export.hpp"

#include <algorithm>
#include <iostream>
#include <stdexcept>
#include <vector>

#include "daemon/records/as_applied_rows.hpp"

namespace weedspray::daemon::maps {
namespace fs = std::filesystem;

ExportSummary export_map(const ExportOptions& o) {
  std::error_code ec;
  if (!fs::is_directory(o.log_dir, ec))
    throw std::runtime_error(o.log_dir.string() + ": not a folder (the as-applied log folder)");
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(o.log_dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("as-applied-") && name.ends_with(".csv")) files.push_back(entry.path());
  }
  if (ec) throw std::runtime_error(o.log_dir.string() + ": " + ec.message());
  if (files.empty()) throw std::runtime_error(o.log_dir.string() + ": no as-applied-*.csv files");
  std::sort(files.begin(), files.end());  // names carry their creation time

  ExportSummary summary;
  OgrMapWriter writer(o.format, o.out, o.overwrite);
  DensityGrid grid(o.cell_m);
  std::unique_ptr<StretchBuilder> stretches;
  std::size_t nozzles = 0;
  auto emit = [&](const Stretch& s) {
    writer.add(s);
    ++summary.stretches;
    summary.volume_l += s.volume_l;
    summary.area_m2 += s.area_m2;
  };
  AsAppliedRow row;
  bool have_previous = false;
  double previous_time_s = 0;
  double period_s = 0;  // the last regular record interval: what a record after a gap covers
  for (const fs::path& file : files) {
    AsAppliedRows rows(file);
    ++summary.files;
    if (!rows.has_map_columns()) {
      ++summary.files_without_position;
      std::cerr << "weedspray-export-map: " << file.string()
                << ": written before the map columns (no positions): skipped\n";
      continue;
    }
    if (rows.nozzles() != nozzles) {
      if (stretches) stretches->end_all();
      nozzles = rows.nozzles();
      stretches = std::make_unique<StretchBuilder>(nozzles, o.stretch, emit);
    }
    while (rows.next(row)) {
      const bool in_window = (!o.from_utc_ns && !o.to_utc_ns) ||
                             (row.utc_ns != 0 && (!o.from_utc_ns || row.utc_ns >= *o.from_utc_ns) &&
                              (!o.to_utc_ns || row.utc_ns <= *o.to_utc_ns));
      const double since = row.time_s - previous_time_s;
      const bool continues = have_previous && since > 0 && since <= o.max_gap_s;
      previous_time_s = row.time_s;
      have_previous = true;
      if (continues) period_s = since;
      if (!continues || !in_window) stretches->end_all();
      if (!in_window) continue;
      ++summary.records;
      stretches->add(row, continues ? since : period_s);  // ends a stretch where unplaced
      if (!row.has_position) continue;
      ++summary.records_with_position;
      if (row.nozzles_placed) {
        for (std::size_t n = 0; n < nozzles; ++n) {
          grid.add(row.patch[n], row.density[n], row.crop_density[n]);
        }
      } else {
        // A position but no heading (standing still): the boom's mean at the antenna.
        double weed = 0, crop = 0;
        for (std::size_t n = 0; n < nozzles; ++n) {
          weed += row.density[n];
          crop += row.crop_density[n];
        }
        grid.add(row.antenna, weed / static_cast<double>(nozzles),
                 crop / static_cast<double>(nozzles));
      }
    }
    summary.torn_or_damaged_lines += rows.torn_tail_lines() + rows.damaged_lines();
  }
  if (stretches) stretches->end_all();
  for (const DensityCell& cell : grid.cells()) writer.add(cell);
  summary.cells = grid.size();
  writer.close();
  return summary;
}

}  // namespace weedspray::daemon::maps
