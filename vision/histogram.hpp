// SPDX-License-Identifier: Apache-2.0
// The 256-bin histogram of an 8-bit vegetation-index image, and the class statistics the
// threshold methods share.
#pragma once

#include <array>
#include <cstdint>

namespace weedspray::vision {

using Histogram = std::array<std::uint32_t, 256>;

// Pixel count and intensity sum over the bins [first, last] (inclusive).
struct HistogramRange {
  std::uint64_t count = 0;
  std::uint64_t sum = 0;  // sum of bin * count
  double mean() const { return count == 0 ? 0.0 : static_cast<double>(sum) / count; }
};

HistogramRange histogram_range(const Histogram& histogram, int first, int last);
std::uint64_t histogram_total(const Histogram& histogram);

// The most populated level (the lowest one on a tie); 0 for an empty histogram.
int histogram_peak(const Histogram& histogram);

}  // namespace weedspray::vision
