// SPDX-License-Identifier: Apache-2.0
#include "vision/weed_inter_row.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace weedspray::vision {
namespace {

// Box filter over +-half_window columns (the window shrinks at the edges).
void smooth_columns(std::span<const std::uint32_t> counts, int half_window,
                    std::vector<double>& smoothed) {
  const int n = static_cast<int>(counts.size());
  smoothed.resize(counts.size());
  double sum = 0.0;
  int lo = 0;
  int hi = -1;  // the window is [lo, hi]
  for (int x = 0; x < n; ++x) {
    while (hi < std::min(n - 1, x + half_window)) sum += counts[++hi];
    while (lo < x - half_window) sum -= counts[lo++];
    smoothed[x] = sum / (hi - lo + 1);
  }
}

}  // namespace

std::size_t find_row_peaks(std::span<const std::uint32_t> column_counts, const InterRowRule& rule,
                           std::vector<double>& smoothed_scratch,
                           std::span<double, kMaxCropRows> out) {
  const int n = static_cast<int>(column_counts.size());
  if (n == 0) return 0;
  const int half_window =
      std::max(1, static_cast<int>(std::lround(rule.row_band_fraction * n / 4.0)));
  smooth_columns(column_counts, half_window, smoothed_scratch);
  const std::vector<double>& s = smoothed_scratch;
  const double tallest = *std::max_element(s.begin(), s.end());
  if (tallest <= 0.0) return 0;
  const double limit = rule.peak_fraction * tallest;

  // Local maxima (a plateau counts once, at its middle); the tallest kept when there are many.
  constexpr std::size_t kMaxCandidates = 64;
  std::array<std::pair<double, int>, kMaxCandidates> candidates{};  // (height, column)
  std::size_t found = 0;
  for (int x = 0; x < n;) {
    int end = x;
    while (end + 1 < n && s[end + 1] == s[x]) ++end;
    const bool above_left = x == 0 || s[x] > s[x - 1];
    const bool above_right = end == n - 1 || s[x] > s[end + 1];
    if (s[x] > limit && above_left && above_right) {
      const std::pair<double, int> peak{s[x], (x + end) / 2};
      if (found < kMaxCandidates) {
        candidates[found++] = peak;
      } else {
        auto lowest = std::min_element(candidates.begin(), candidates.end());
        if (*lowest < peak) *lowest = peak;
      }
    }
    x = end + 1;
  }
  std::sort(candidates.begin(), candidates.begin() + found, std::greater<>());

  // Non-maximum suppression: rows closer than min_row_spacing are one row, the taller wins.
  const double min_spacing = rule.min_row_spacing * n;
  std::size_t rows = 0;
  for (std::size_t i = 0; i < found && rows < out.size(); ++i) {
    const double position = (candidates[i].second + 0.5) / n;
    const bool far = std::all_of(out.begin(), out.begin() + rows, [&](double accepted) {
      return std::abs(accepted - position) * n >= min_spacing;
    });
    if (far) out[rows++] = position;
  }
  std::sort(out.begin(), out.begin() + rows);
  return rows;
}

CropRowTracker::CropRowTracker(const InterRowRule& rule) : rule_(rule) {}

void CropRowTracker::update(std::span<const std::uint32_t> column_counts) {
  std::array<double, kMaxCropRows> peaks{};
  const std::size_t peak_count = find_row_peaks(column_counts, rule_, smoothed_, peaks);
  std::array<bool, kMaxCropRows> used{};

  // Each tracked row takes the nearest free peak within the gate, or counts a miss.
  for (std::size_t r = 0; r < count_; ++r) {
    CropRow& row = rows_[r];
    std::size_t best = peak_count;
    double best_distance = rule_.track_gate;
    for (std::size_t p = 0; p < peak_count; ++p) {
      const double distance = std::abs(peaks[p] - row.position);
      if (!used[p] && distance <= best_distance) {
        best = p;
        best_distance = distance;
      }
    }
    if (best == peak_count) {
      ++row.misses;
      continue;
    }
    used[best] = true;
    row.position += rule_.smoothing * (peaks[best] - row.position);
    ++row.hits;
    row.misses = 0;
    row.confirmed = row.confirmed || row.hits >= rule_.confirm_frames;
  }

  // Lost rows go; a tentative row must be seen in consecutive frames.
  const auto lost = [&](const CropRow& row) {
    return row.misses >= rule_.lost_after_frames || (!row.confirmed && row.misses > 0);
  };
  count_ = static_cast<std::size_t>(std::remove_if(rows_.begin(), rows_.begin() + count_, lost) -
                                    rows_.begin());

  // Unclaimed peaks far from every row start rows; with no confirmed row left they count at
  // once (first frame, or the rows were lost: re-acquire rather than wait).
  const bool acquiring = std::none_of(rows_.begin(), rows_.begin() + count_,
                                      [&](const CropRow& row) { return row.confirmed; });
  for (std::size_t p = 0; p < peak_count && count_ < kMaxCropRows; ++p) {
    if (used[p]) continue;
    const bool far = std::all_of(rows_.begin(), rows_.begin() + count_, [&](const CropRow& row) {
      return std::abs(row.position - peaks[p]) >= rule_.min_row_spacing;
    });
    if (!far) continue;
    rows_[count_++] = {peaks[p], 1, 0, acquiring || rule_.confirm_frames <= 1};
  }
  std::sort(rows_.begin(), rows_.begin() + count_,
            [](const CropRow& a, const CropRow& b) { return a.position < b.position; });
}

void CropRowTracker::mark_bands(std::span<std::uint8_t> in_band) const {
  std::fill(in_band.begin(), in_band.end(), std::uint8_t{0});
  const double n = static_cast<double>(in_band.size());
  const double half = rule_.row_band_fraction * n / 2.0;
  for (std::size_t r = 0; r < count_; ++r) {
    if (!rows_[r].confirmed) continue;
    const double centre = rows_[r].position * n;
    const auto first = static_cast<std::ptrdiff_t>(std::max(0.0, std::round(centre - half)));
    const auto last = static_cast<std::ptrdiff_t>(std::min(n, std::round(centre + half)));
    for (std::ptrdiff_t x = first; x < last; ++x) in_band[x] = 1;
  }
}

}  // namespace weedspray::vision
