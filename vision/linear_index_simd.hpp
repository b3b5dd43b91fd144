// SPDX-License-Identifier: Apache-2.0
// SIMD kernels for the indices that are linear in R, G, B (cive, exg_raw): index and
// histogram in one pass over packed 24-bit frames, and CIVE over YUYV frames (internal to
// vision/).
#pragma once

#include <cstddef>
#include <cstdint>

#include "vision/histogram.hpp"
#include "vision/image_view.hpp"
#include "vision/vegetation_index.hpp"

namespace weedspray::vision {

void cive_rows_simd(const ImageView& frame, PixelRect rect, std::uint8_t* out,
                    std::size_t out_stride, Histogram& histogram);
// CIVE straight from YUYV (cive_of_yuv); rect.x and rect.width even.
void cive_yuyv_rows_simd(const ImageView& frame, PixelRect rect, std::uint8_t* out,
                         std::size_t out_stride, Histogram& histogram);
void exg_raw_rows_simd(const ImageView& frame, PixelRect rect, std::uint8_t* out,
                       std::size_t out_stride, Histogram& histogram);

}  // namespace weedspray::vision
