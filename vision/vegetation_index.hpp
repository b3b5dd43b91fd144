// SPDX-License-Identifier: Apache-2.0
// Vegetation indices ("graying"): colour frame -> one 8-bit plane where plants are bright.
//
// Every index is mapped to 8 bits with a FIXED scale (never per-frame min-max), so a threshold
// means the same thing on every frame:
//   exg_norm   ExG = 2g - r - b on chromatic coordinates (r = R/(R+G+B) ...), in [-1, 2];
//              v = round((ExG + 1) * 255 / 3), so 85 is ExG = 0; equals round(255 G / (R+G+B)).
//              Black pixels (R+G+B = 0) map to 85 (no colour, not a plant).
//   exg_raw    2G - R - B on bytes, in [-510, 510]; v = round((ExG + 510) / 4), 128 is ExG = 0.
//   exg_exr    ExG - ExR on chromatic coordinates, ExR = 1.4 r - g, so ExG - ExR = 3g - 2.4r - b,
//              in [-2.4, 3]; v = round((x + 2.4) * 255 / 5.4) = round(255 (54 G + 14 B) / (54 S))
//              with S = R + G + B, halves up; 113 is 0 (Meyer's zero threshold), grey and
//              black (no colour) are 107.
//   cive       CIVE = 0.441 R - 0.811 G + 0.385 B + 18.78745 (Kataoka), plants low, so
//              v = 128 - (CIVE - 18.78745) / 2 in 7-bit fixed point:
//              v = (16448 + 52 G - 28 R - 25 B) >> 7 (range 22..232, 128 is CIVE = 18.79;
//              coefficients within 1.5 % of Kataoka's, and 16-bit SIMD friendly).
//              YUYV frames: CIVE is linear in R, G, B and so in Y, U, V (BT.601 limited range);
//              it is computed from them directly, without converting to RGB (cive_of_yuv):
//              v = max(0, 36670 - Y - 71 U - 87 V) >> 7, capped at 255. In-gamut colours
//              agree with the RGB formula within a level or two; colours outside the RGB
//              gamut are not clipped first.
//   max_value  max(R, G, B) (the UGV paper's "maximum value method" of graying).
//   weighted   0.299 R + 0.587 G + 0.114 B (weighted gray; Y for YUYV frames).
//   mono       the camera's own grey level: GREY bytes as they are, Y of YUYV, weighted gray
//              of colour frames.
//   exg_chroma 255 G / (R+G+B) with dark pixels (R+G+B < 3 * kDarkLevel) forced to 85: the
//              normalised ExG without the noise chromaticity has in deep shadow.
// GREY frames carry no colour: every colour index falls back to the mono pass-through on them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "vision/histogram.hpp"
#include "vision/image_view.hpp"

namespace weedspray::vision {

// Fixed levels of the 8-bit scales.
inline constexpr std::uint8_t kExgZeroLevel = 85;      // exg_norm / exg_chroma: ExG = 0
inline constexpr std::uint8_t kExgExrGreyLevel = 107;  // exg_exr of any grey (and black)
inline constexpr int kCiveOffset = 16448;              // 128.5 * 2^7: level 128 plus rounding
inline constexpr int kDarkLevel = 16;  // exg_chroma: mean channel below this is "no colour"

enum class VegetationIndex : std::uint8_t {
  kExgNormalized,
  kExgRaw,
  kExgMinusExr,
  kCive,
  kMaxValue,
  kWeightedGray,
  kMono,
  kExgChroma,
};

// Config names: "exg_norm", "exg_raw", "exg_exr", "cive", "max_value", "weighted", "mono",
// "exg_chroma".
std::string_view to_string(VegetationIndex index);
std::optional<VegetationIndex> parse_vegetation_index(std::string_view name);
std::span<const VegetationIndex> all_vegetation_indices();
std::span<const std::string_view> vegetation_index_names();

// Pixel rectangle of a frame, in pixels.
struct PixelRect {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
};

// Computes the index over `rect` of `frame` into `out` (rect.width x rect.height bytes, rows
// `out_stride` apart) and ADDS each value to `histogram` (one pass over the frame).
// For YUYV frames rect.x and rect.width must be even. Pure, allocation-free.
void compute_vegetation_index(const ImageView& frame, VegetationIndex index, PixelRect rect,
                              std::uint8_t* out, std::size_t out_stride, Histogram& histogram);

// The index's fixed threshold level: the best single threshold shared by all 142 images of
// data/ews-train (weedspray-lab vision-eval --bounds), used where a frame's histogram cannot
// be split (unimodal, degenerate).
int default_fixed_threshold(VegetationIndex index);

// CIVE of one YUYV pixel (see above).
inline std::uint8_t cive_of_yuv(std::uint8_t y, std::uint8_t u, std::uint8_t v) {
  const int scaled = 36670 - y - 71 * u - 87 * v;
  return static_cast<std::uint8_t>(scaled <= 0 ? 0 : (scaled >> 7 > 255 ? 255 : scaled >> 7));
}

// The index value of one pixel (reference implementation, used by tests and the lab tool).
std::uint8_t vegetation_index_of(VegetationIndex index, std::uint8_t red, std::uint8_t green,
                                 std::uint8_t blue);

}  // namespace weedspray::vision
