// SPDX-License-Identifier: Apache-2.0
// Crop rows for the inter-row rule: peaks of the column histogram of the vegetation mask,
// tracked from frame to frame (pure; allocation-free after the first frame of a given width).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "vision/weed_source.hpp"

namespace weedspray::vision {

inline constexpr std::size_t kMaxCropRows = 16;

struct CropRow {
  double position = 0.0;   // centre, share of the region's width (0..1)
  int hits = 0;            // frames in which a peak confirmed it
  int misses = 0;          // frames since it was last seen
  bool confirmed = false;  // takes part in the rule (seen confirm_frames times, or acquired)
};

// Peaks of the column histogram (smoothed over half a row band): local maxima above
// rule.peak_fraction of the tallest column, at least rule.min_row_spacing apart (the taller
// wins). Positions are shares of the width, written to `out`; returns how many.
std::size_t find_row_peaks(std::span<const std::uint32_t> column_counts, const InterRowRule& rule,
                           std::vector<double>& smoothed_scratch,
                           std::span<double, kMaxCropRows> out);

class CropRowTracker {
 public:
  explicit CropRowTracker(const InterRowRule& rule);

  // One frame's column histogram. A tracked row moves towards the nearest peak within
  // rule.track_gate (exponential smoothing) or counts a miss; a row missed for
  // rule.lost_after_frames frames is dropped. A peak near no row starts a new row when it is
  // at least min_row_spacing from every row; with no confirmed rows (start, or all lost) new
  // rows count at once (re-acquisition), otherwise after rule.confirm_frames sightings.
  void update(std::span<const std::uint32_t> column_counts);
  void reset() { count_ = 0; }

  // Tracked rows, tentative ones included, left to right.
  std::span<const CropRow> rows() const { return {rows_.data(), count_}; }
  // in_band[x] = 1 when column x of a width-column region lies in a confirmed row's band.
  void mark_bands(std::span<std::uint8_t> in_band) const;

 private:
  InterRowRule rule_;
  std::array<CropRow, kMaxCropRows> rows_{};
  std::size_t count_ = 0;
  std::vector<double> smoothed_;
};

}  // namespace weedspray::vision
