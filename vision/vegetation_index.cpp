// SPDX-License-Identifier: Apache-2.0
#include "vision/vegetation_index.hpp"

#include <algorithm>
#include <array>

#include "vision/index_kernels.hpp"

namespace weedspray::vision {
namespace {

constexpr std::array kIndices = {
    VegetationIndex::kExgNormalized, VegetationIndex::kExgRaw,    VegetationIndex::kExgMinusExr,
    VegetationIndex::kCive,          VegetationIndex::kMaxValue,  VegetationIndex::kWeightedGray,
    VegetationIndex::kMono,          VegetationIndex::kExgChroma,
};
constexpr std::array<std::string_view, kIndices.size()> kIndexNames = {
    "exg_norm", "exg_raw", "exg_exr", "cive", "max_value", "weighted", "mono", "exg_chroma",
};

}  // namespace

std::string_view to_string(VegetationIndex index) {
  return kIndexNames[static_cast<std::size_t>(index)];
}

std::optional<VegetationIndex> parse_vegetation_index(std::string_view name) {
  for (std::size_t i = 0; i < kIndices.size(); ++i) {
    if (kIndexNames[i] == name) return kIndices[i];
  }
  return std::nullopt;
}

std::span<const VegetationIndex> all_vegetation_indices() {
  return kIndices;
}
std::span<const std::string_view> vegetation_index_names() {
  return kIndexNames;
}

int default_fixed_threshold(VegetationIndex index) {
  switch (index) {
    case VegetationIndex::kExgNormalized:
      return 91;
    case VegetationIndex::kExgChroma:
      return 91;
    case VegetationIndex::kExgRaw:
      return 133;
    case VegetationIndex::kExgMinusExr:
      return 110;
    case VegetationIndex::kCive:
      return 131;
    // Grey levels do not separate plants from soil by colour; these are the measured best
    // shared levels, kept only so every index has an answer.
    case VegetationIndex::kMaxValue:
      return 43;
    case VegetationIndex::kWeightedGray:
      return 39;
    case VegetationIndex::kMono:
      return 39;
  }
  return 128;
}

std::uint8_t vegetation_index_of(VegetationIndex index, std::uint8_t red, std::uint8_t green,
                                 std::uint8_t blue) {
  const int r = red;
  const int g = green;
  const int b = blue;
  const int sum = r + g + b;
  switch (index) {
    case VegetationIndex::kExgNormalized:
      // round(255 g / s) with halves rounded up, in integers.
      return sum == 0 ? kExgZeroLevel : static_cast<std::uint8_t>((510 * g + sum) / (2 * sum));
    case VegetationIndex::kExgChroma:
      return sum < 3 * kDarkLevel ? kExgZeroLevel
                                  : static_cast<std::uint8_t>((510 * g + sum) / (2 * sum));
    case VegetationIndex::kExgRaw:
      // (2G - R - B + 510) / 4, rounded half up.
      return static_cast<std::uint8_t>((2 * g - r - b + 510 + 2) / 4);
    case VegetationIndex::kExgMinusExr:
      // (x + 2.4) * 255 / 5.4 = 255 (54 G + 14 B) / (54 S): rounded half up, in integers.
      return sum == 0
                 ? kExgExrGreyLevel
                 : static_cast<std::uint8_t>((510 * (54 * g + 14 * b) + 54 * sum) / (108 * sum));
    case VegetationIndex::kCive:
      return static_cast<std::uint8_t>((kCiveOffset + 52 * g - 28 * r - 25 * b) >> 7);
    case VegetationIndex::kMaxValue:
      return static_cast<std::uint8_t>(std::max({r, g, b}));
    case VegetationIndex::kWeightedGray:
    case VegetationIndex::kMono:
      return weighted_gray(red, green, blue);
  }
  return 0;
}

void compute_vegetation_index(const ImageView& frame, VegetationIndex index, PixelRect rect,
                              std::uint8_t* out, std::size_t out_stride, Histogram& histogram) {
  switch (frame.format) {
    case PixelFormat::kGrey:
      index_rows_grey(frame, rect, out, out_stride, histogram);
      return;
    case PixelFormat::kYuyv:
      index_rows_yuyv(frame, index, rect, out, out_stride, histogram);
      return;
    case PixelFormat::kBgr24:
    case PixelFormat::kRgb24:
      index_rows_packed_rgb(frame, index, rect, out, out_stride, histogram);
      return;
  }
}

}  // namespace weedspray::vision
