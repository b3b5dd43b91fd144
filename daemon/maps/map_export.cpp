// SPDX-License-Identifier: Apache-2.0
#include "daemon/maps/map_export.hpp"

#include <algorithm>
#include <iostream>
#include <memory>
#include <set>
#include <stdexcept>

#include "daemon/records/as_applied_reader.hpp"
#include "daemon/records/as_applied_rows.hpp"

namespace weedspray::daemon::maps {
namespace fs = std::filesystem;

namespace {

// A folder's files, checked before anything is written.
std::vector<fs::path> folder_files(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw std::runtime_error(dir.string() + ": not a folder (the as-applied log folder)");
  std::vector<fs::path> files = as_applied_files(dir);  // names carry their creation time
  if (files.empty()) throw std::runtime_error(dir.string() + ": no as-applied-*.csv files");
  return files;
}

// One board's log folder into the map: its stretches (named `board` when not empty) and its
// samples in the shared grid. The clock, the nozzles and the open stretches are the board's own.
class BoardExport {
 public:
  BoardExport(const ExportOptions& o, OgrMapWriter& writer, DensityGrid& grid,
              ExportSummary& summary, std::string board)
      : o_(o), writer_(writer), grid_(grid), summary_(summary), board_(std::move(board)) {}

  void read(const std::vector<fs::path>& files) {
    for (const fs::path& file : files) read(file);
    if (stretches_) stretches_->end_all();
  }

 private:
  void read(const fs::path& file) {
    AsAppliedRows rows(file);
    ++summary_.files;
    if (!rows.has_map_columns()) {
      ++summary_.files_without_position;
      std::cerr << "weedspray-export-map: " << file.string()
                << ": written before the map columns (no positions): skipped\n";
      return;
    }
    if (rows.nozzles() != nozzles_) {
      if (stretches_) stretches_->end_all();
      nozzles_ = rows.nozzles();
      stretches_ = std::make_unique<StretchBuilder>(nozzles_, o_.stretch,
                                                    [this](const Stretch& s) { emit(s); });
    }
    while (rows.next(row_)) add(row_);
    summary_.torn_or_damaged_lines += rows.torn_tail_lines() + rows.damaged_lines();
  }

  void emit(const Stretch& s) {
    writer_.add(s, board_);
    ++summary_.stretches;
    summary_.volume_l += s.volume_l;
    summary_.area_m2 += s.area_m2;
  }

  void add(const AsAppliedRow& row) {
    const bool in_window = (!o_.from_utc_ns && !o_.to_utc_ns) ||
                           (row.utc_ns != 0 && (!o_.from_utc_ns || row.utc_ns >= *o_.from_utc_ns) &&
                            (!o_.to_utc_ns || row.utc_ns <= *o_.to_utc_ns));
    const double since = row.time_s - previous_time_s_;
    const bool continues = have_previous_ && since > 0 && since <= o_.max_gap_s;
    previous_time_s_ = row.time_s;
    have_previous_ = true;
    if (continues) period_s_ = since;
    if (!continues || !in_window) stretches_->end_all();
    if (!in_window) return;
    ++summary_.records;
    stretches_->add(row, continues ? since : period_s_);  // ends a stretch where unplaced
    if (!row.has_position) return;
    ++summary_.records_with_position;
    if (row.nozzles_placed) {
      for (std::size_t n = 0; n < nozzles_; ++n) {
        grid_.add(row.patch[n], row.density[n], row.crop_density[n]);
      }
      return;
    }
    // A position but no heading (standing still): the boom's mean at the antenna.
    double weed = 0, crop = 0;
    for (std::size_t n = 0; n < nozzles_; ++n) {
      weed += row.density[n];
      crop += row.crop_density[n];
    }
    grid_.add(row.antenna, weed / static_cast<double>(nozzles_),
              crop / static_cast<double>(nozzles_));
  }

  const ExportOptions& o_;
  OgrMapWriter& writer_;
  DensityGrid& grid_;
  ExportSummary& summary_;
  std::string board_;
  std::unique_ptr<StretchBuilder> stretches_;
  std::size_t nozzles_ = 0;
  AsAppliedRow row_;
  bool have_previous_ = false;
  double previous_time_s_ = 0;
  double period_s_ = 0;  // the last regular record interval: what a record after a gap covers
};

// The folder as a list of names, the last first; "a/b/" and "a/b/." are "b", "a".
std::vector<std::string> components_last_first(const fs::path& dir) {
  fs::path p = fs::absolute(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  std::vector<std::string> names;
  for (const fs::path& part : p) {
    if (!part.empty() && part != p.root_path()) names.insert(names.begin(), part.string());
  }
  return names;
}

std::string last_components(const std::vector<std::string>& last_first, std::size_t count) {
  std::string name;
  for (std::size_t i = std::min(count, last_first.size()); i-- > 0;) {
    name += last_first[i];
    if (i > 0) name += '/';
  }
  return name;
}

}  // namespace

std::vector<std::string> board_names(const std::vector<fs::path>& dirs) {
  std::vector<std::vector<std::string>> parts;
  for (const fs::path& dir : dirs) parts.push_back(components_last_first(dir));
  std::vector<std::string> names;
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    std::size_t count = 1;
    auto clashes = [&] {
      for (std::size_t j = 0; j < dirs.size(); ++j) {
        if (j != i && last_components(parts[j], count) == last_components(parts[i], count))
          return true;
      }
      return false;
    };
    while (clashes() && count < parts[i].size()) ++count;
    names.push_back(last_components(parts[i], count));
  }
  if (std::set<std::string>(names.begin(), names.end()).size() != names.size())
    throw std::runtime_error("a log folder is given twice (--dir)");
  return names;
}

ExportSummary export_map(const ExportOptions& o) {
  if (o.log_dirs.empty()) throw std::runtime_error("no as-applied log folder");
  std::vector<std::vector<fs::path>> files;
  for (const fs::path& dir : o.log_dirs) files.push_back(folder_files(dir));
  const bool several = o.log_dirs.size() > 1;
  const std::vector<std::string> boards =
      several ? board_names(o.log_dirs) : std::vector<std::string>{""};

  ExportSummary summary;
  OgrMapWriter writer(o.format, o.out, o.overwrite, several);
  DensityGrid grid(o.cell_m);
  for (std::size_t i = 0; i < o.log_dirs.size(); ++i) {
    const std::uint64_t placed_before = summary.records_with_position;
    BoardExport(o, writer, grid, summary, boards[i]).read(files[i]);
    if (summary.records_with_position == placed_before)
      summary.dirs_without_position.push_back(o.log_dirs[i]);
  }
  for (const DensityCell& cell : grid.cells()) writer.add(cell);
  summary.cells = grid.size();
  writer.close();
  return summary;
}

}  // namespace weedspray::daemon::maps
