// SPDX-License-Identifier: Apache-2.0
#include "vision/histogram.hpp"

#include <algorithm>

namespace weedspray::vision {

HistogramRange histogram_range(const Histogram& histogram, int first, int last) {
  HistogramRange range;
  for (int level = std::max(first, 0); level <= std::min(last, 255); ++level) {
    range.count += histogram[level];
    range.sum += static_cast<std::uint64_t>(histogram[level]) * level;
  }
  return range;
}

std::uint64_t histogram_total(const Histogram& histogram) {
  return histogram_range(histogram, 0, 255).count;
}

int histogram_peak(const Histogram& histogram) {
  return static_cast<int>(std::max_element(histogram.begin(), histogram.end()) - histogram.begin());
}

}  // namespace weedspray::vision
