// SPDX-License-Identifier: Apache-2.0
// Small synthetic frames for the vision tests.
#pragma once

#include <cstdint>
#include <vector>

#include "vision/image_view.hpp"

namespace weedspray::vision::test {

struct Bgr {
  std::uint8_t b, g, r;
};

// A packed BGR frame owning its bytes, with optional row padding.
struct BgrFrame {
  int width = 0;
  int height = 0;
  std::size_t stride = 0;
  std::vector<std::uint8_t> bytes;

  BgrFrame(int w, int h, Bgr fill, std::size_t padding = 0)
      : width(w),
        height(h),
        stride(static_cast<std::size_t>(w) * 3 + padding),
        bytes(stride * h, 0) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) set(x, y, fill);
    }
  }
  void set(int x, int y, Bgr c) {
    std::uint8_t* p = &bytes[y * stride + x * 3];
    p[0] = c.b;
    p[1] = c.g;
    p[2] = c.r;
  }
  ImageView view() const { return {bytes.data(), width, height, stride, PixelFormat::kBgr24}; }
};

inline constexpr Bgr kSoil{70, 100, 130};  // brown: CIVE level 127
inline constexpr Bgr kPlant{40, 150, 60};  // green: CIVE level 168
inline constexpr Bgr kBlack{0, 0, 0};
inline constexpr Bgr kWhite{255, 255, 255};

}  // namespace weedspray::vision::test
