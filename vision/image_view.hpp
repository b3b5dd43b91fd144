// SPDX-License-Identifier: Apache-2.0
// A non-owning view of one camera frame or image, shared by io/ (cameras produce it) and
// vision/ (the pipeline consumes it) so frames are never copied on the way.
#pragma once

#include <cstddef>
#include <cstdint>

namespace weedspray::vision {

enum class PixelFormat : std::uint8_t {
  kBgr24,  // 3 bytes per pixel, B G R (OpenCV's order)
  kRgb24,  // 3 bytes per pixel, R G B (V4L2 RGB24)
  kYuyv,   // 4 bytes per 2 pixels, Y0 U Y1 V (V4L2 YUYV)
  kGrey,   // 1 byte per pixel (mono industrial cameras)
};

struct ImageView {
  const std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  std::size_t stride = 0;  // bytes from one row to the next
  PixelFormat format = PixelFormat::kBgr24;
};

}  // namespace weedspray::vision
