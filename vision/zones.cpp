// SPDX-License-Identifier: Apache-2.0
#include "vision/zones.hpp"

#include <algorithm>

namespace weedspray::vision {

std::string_view to_string(DensityLevel level) {
  switch (level) {
    case DensityLevel::kNone:
      return "none";
    case DensityLevel::kFew:
      return "few";
    case DensityLevel::kModerate:
      return "moderate";
    case DensityLevel::kMany:
      return "many";
    case DensityLevel::kSevere:
      return "severe";
    case DensityLevel::kVerySevere:
      return "very_severe";
  }
  return "unknown";
}

DensityLevel classify_density(double density, const DensityLevelCuts& cuts) {
  int level = 0;
  while (level < static_cast<int>(cuts.upper.size()) && density > cuts.upper[level]) ++level;
  return static_cast<DensityLevel>(level);
}

std::optional<std::string_view> validate_density_cuts(const DensityLevelCuts& cuts) {
  double previous = -1.0;
  for (double cut : cuts.upper) {
    if (!(cut >= 0.0 && cut <= 1.0)) return "density level cut points must lie in [0, 1]";
    if (!(cut > previous)) return "density level cut points must be strictly increasing";
    previous = cut;
  }
  return std::nullopt;
}

void find_inter_row_intervals(std::span<const std::uint32_t> column_counts,
                              std::uint64_t region_pixels, double fraction_of_max,
                              const DensityLevelCuts& cuts, InterRowMap& out) {
  out.count = 0;
  if (column_counts.empty() || region_pixels == 0) return;
  const std::uint32_t max_count = *std::max_element(column_counts.begin(), column_counts.end());
  const double limit = fraction_of_max * max_count;
  const int columns = static_cast<int>(column_counts.size());
  int column = 0;
  while (column < columns) {
    if (column_counts[column] > limit) {
      ++column;
      continue;
    }
    const int first = column;
    std::uint64_t pixels = 0;
    while (column < columns && column_counts[column] <= limit) pixels += column_counts[column++];
    const double share = static_cast<double>(pixels) / static_cast<double>(region_pixels);
    if (out.count == kMaxInterRowIntervals) {
      // Out of room: fold this interval into the last one rather than drop its weeds.
      InterRowInterval& last = out.intervals[out.count - 1];
      last.last_column = column - 1;
      last.share += share;
      last.level = classify_density(last.share, cuts);
      continue;
    }
    out.intervals[out.count++] = {first, column - 1, share, classify_density(share, cuts)};
  }
}

}  // namespace weedspray::vision
