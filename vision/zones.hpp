// SPDX-License-Identifier: Apache-2.0
// Weed density per nozzle zone and the 2018 paper's inter-row (lateral histogram) weed map.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace weedspray::vision {

// Part of the frame that images the ground the boom will spray, as fractions of the frame
// (0 <= left < right <= 1, 0 <= top < bottom <= 1).
struct RegionOfInterest {
  double left = 0.0;
  double top = 0.0;
  double right = 1.0;
  double bottom = 1.0;
};

// The six density levels of the 2018 paper.
enum class DensityLevel : std::uint8_t { kNone, kFew, kModerate, kMany, kSevere, kVerySevere };
std::string_view to_string(DensityLevel level);  // "none", "few", "moderate", "many", ...

// A density d (0..1) is level k when cut[k-1] < d <= cut[k] (cut[-1] = -inf): d <= upper[0]
// is kNone, d > upper[4] is kVerySevere. Must be strictly increasing.
struct DensityLevelCuts {
  std::array<double, 5> upper = {0.005, 0.02, 0.05, 0.10, 0.20};
};
DensityLevel classify_density(double density, const DensityLevelCuts& cuts);
// nullopt if the cut points are not strictly increasing within [0, 1].
std::optional<std::string_view> validate_density_cuts(const DensityLevelCuts& cuts);

// One inter-row interval of columns [first_column, last_column] (inclusive, relative to the
// region of interest) where the column count is <= fraction * max column count.
struct InterRowInterval {
  int first_column = 0;
  int last_column = 0;
  double share = 0.0;  // p(n): vegetation pixels in the interval / pixels of the region
  DensityLevel level = DensityLevel::kNone;
};

inline constexpr std::size_t kMaxInterRowIntervals = 64;

struct InterRowMap {
  std::array<InterRowInterval, kMaxInterRowIntervals> intervals{};
  std::size_t count = 0;  // intervals beyond the capacity are merged into the last one
  std::span<const InterRowInterval> view() const { return {intervals.data(), count}; }
};

// The 2018 paper's lateral histogram: `column_counts` holds the vegetation pixels of each
// column of the region (`region_pixels` pixels in all). Allocation-free.
void find_inter_row_intervals(std::span<const std::uint32_t> column_counts,
                              std::uint64_t region_pixels, double fraction_of_max,
                              const DensityLevelCuts& cuts, InterRowMap& out);

}  // namespace weedspray::vision
