// SPDX-License-Identifier: Apache-2.0
// The live view's picture: a camera frame with its segmentation and zone grid drawn in, as
// sprayctl snapshot and weedspray-lab vision-segment write it. Pure: no threads, no I/O.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "vision/image_view.hpp"
#include "vision/vegetation_index.hpp"

namespace weedspray::vision {

// Overlay colours, B G R: crop blue and weed red (colours never seen in a field), the zone
// grid yellow. Soil is the frame dimmed to 60 %.
struct OverlayColour {
  std::uint8_t b, g, r;
  bool operator==(const OverlayColour&) const = default;
};
inline constexpr OverlayColour kOverlayCrop{255, 0, 0};
inline constexpr OverlayColour kOverlayWeed{0, 0, 255};
inline constexpr OverlayColour kOverlayGrid{0, 255, 255};

// The zone grid over the region of interest, as Pipeline cuts it: zone (row, col) spans
// columns [col * width / cols, (col + 1) * width / cols) of the region, rows likewise.
struct OverlayZones {
  int rows = 1;
  int cols = 1;
  std::span<const double> density;   // rows * cols weed densities 0..1, row-major
  std::span<const double> duty_pct;  // one per column (its nozzle), or empty: not written
};

// A packed BGR image (width * 3 bytes per row) owning its pixels.
struct BgrImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;
  OverlayColour at(int x, int y) const {
    const std::uint8_t* p = &pixels[(static_cast<std::size_t>(y) * width + x) * 3];
    return {p[0], p[1], p[2]};
  }
};

// `frame` (any PixelFormat) as BGR at its own size with, inside `region`: soil dimmed, crop and
// weed pixels of `classes` (kClassSoil/kClassCrop/kClassWeed; at the region's size or any
// other, e.g. a network's output, scaled to it) in their colours, the zone borders as grid
// lines, and each zone's density (and its column's duty) written in it. Throws
// std::invalid_argument when the inputs do not fit together (region outside the frame, too few
// densities, a class map without pixels).
BgrImage draw_overlay(const ImageView& frame, const ImageView& classes, const PixelRect& region,
                      const OverlayZones& zones);

// The image as PNG bytes (in memory), at zlib's fastest level: a live view is sent once, and
// encoding is its main cost.
std::vector<std::uint8_t> encode_png(const BgrImage& image);

}  // namespace weedspray::vision
