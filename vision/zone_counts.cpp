// SPDX-License-Identifier: Apache-2.0
// Vegetation counts with OpenCV universal intrinsics: one compare and one subtract per 16
// pixels (the 0xFF compare mask is -1 in each byte lane).
#include "vision/zone_counts.hpp"

#include <opencv2/core/hal/intrin.hpp>

namespace weedspray::vision {

std::uint32_t count_above(const std::uint8_t* row, int length, std::uint8_t threshold) {
  const cv::v_uint8x16 limit = cv::v_setall_u8(threshold);
  std::uint32_t count = 0;
  int x = 0;
  while (x + 16 <= length) {
    // Byte lanes count up to 255 before they must be widened.
    cv::v_uint8x16 lane_counts = cv::v_setzero_u8();
    for (int block = 0; block < 255 && x + 16 <= length; ++block, x += 16) {
      // v_sub_wrap: OpenCV's operator- saturates on 8-bit lanes.
      lane_counts =
          cv::v_sub_wrap(lane_counts, cv::v_reinterpret_as_u8(cv::v_load(row + x) > limit));
    }
    cv::v_uint16x8 low, high;
    cv::v_expand(lane_counts, low, high);
    count += cv::v_reduce_sum(low + high);
  }
  for (; x < length; ++x) count += row[x] > threshold ? 1u : 0u;
  return count;
}

void accumulate_columns_above(const std::uint8_t* row, int length, std::uint8_t threshold,
                              std::uint32_t* column_counts) {
  for (int x = 0; x < length; ++x) column_counts[x] += row[x] > threshold ? 1u : 0u;
}

}  // namespace weedspray::vision
