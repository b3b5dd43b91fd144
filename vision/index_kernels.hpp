// SPDX-License-Identifier: Apache-2.0
// Row kernels behind compute_vegetation_index (internal to vision/).
#pragma once

#include <cstddef>
#include <cstdint>

#include "vision/histogram.hpp"
#include "vision/image_view.hpp"
#include "vision/vegetation_index.hpp"

namespace weedspray::vision {

// 0.299 R + 0.587 G + 0.114 B in 8-bit fixed point (weights 77, 150, 29 out of 256).
inline std::uint8_t weighted_gray(std::uint8_t red, std::uint8_t green, std::uint8_t blue) {
  return static_cast<std::uint8_t>((77 * red + 150 * green + 29 * blue + 128) >> 8);
}

void index_rows_grey(const ImageView& frame, PixelRect rect, std::uint8_t* out,
                     std::size_t out_stride, Histogram& histogram);
void index_rows_yuyv(const ImageView& frame, VegetationIndex index, PixelRect rect,
                     std::uint8_t* out, std::size_t out_stride, Histogram& histogram);
void index_rows_packed_rgb(const ImageView& frame, VegetationIndex index, PixelRect rect,
                           std::uint8_t* out, std::size_t out_stride, Histogram& histogram);

}  // namespace weedspray::vision
