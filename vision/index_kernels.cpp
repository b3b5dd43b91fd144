// SPDX-License-Identifier: Apache-2.0
// Per-pixel loops of the vegetation indices. Hand-written rather than cv::cvtColor +
// arithmetic because the pipeline needs the index and its histogram in ONE pass over the
// frame, with no temporary images (allocation-free, memory-bandwidth bound on the board).
#include "vision/index_kernels.hpp"

#include "vision/linear_index_simd.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace weedspray::vision {
namespace {

// floor(n / (2 s)) for n < 2^17 and 1 <= s <= 765 by one multiply with a reciprocal table
// (notes/toolchain.md: normalised ExG is 255 G / (R + G + B)). Exact: with m = 2^32 / d
// rounded up, the error n (m - 2^32 / d) / 2^32 < 2^-15 stays below the 1 / d >= 2^-11 gap
// to the next integer (also checked exhaustively in the unit tests).
struct ReciprocalTable {
  std::array<std::uint64_t, 766> multiplier{};
  constexpr ReciprocalTable() {
    for (std::uint64_t s = 1; s < multiplier.size(); ++s) {
      multiplier[s] = (std::uint64_t{1} << 32) / (2 * s) + 1;
    }
  }
};
constexpr ReciprocalTable kReciprocals;

inline std::uint32_t divide_by_twice(std::uint32_t n, int s) {
  return static_cast<std::uint32_t>((n * kReciprocals.multiplier[s]) >> 32);
}

// floor(n / (108 s)) for n < 2^24 and 1 <= s <= 765 (exg_exr), the same way with 2^44: the
// error n / 2^44 < 2^-20 stays below the 1 / (108 s) >= 2^-17 gap; n m < 2^62 fits 64 bits.
struct ExgExrReciprocalTable {
  std::array<std::uint64_t, 766> multiplier{};
  constexpr ExgExrReciprocalTable() {
    for (std::uint64_t s = 1; s < multiplier.size(); ++s) {
      multiplier[s] = (std::uint64_t{1} << 44) / (108 * s) + 1;
    }
  }
};
constexpr ExgExrReciprocalTable kExgExrReciprocals;

inline std::uint32_t divide_by_108_times(std::uint64_t n, int s) {
  return static_cast<std::uint32_t>((n * kExgExrReciprocals.multiplier[s]) >> 44);
}

// One pixel's index given R, G, B; the reference semantics of vegetation_index_of, with the
// expensive ones on integer arithmetic.
template <VegetationIndex kIndex>
inline std::uint8_t pixel_index(int r, int g, int b) {
  if constexpr (kIndex == VegetationIndex::kExgNormalized ||
                kIndex == VegetationIndex::kExgChroma) {
    const int sum = r + g + b;
    if (kIndex == VegetationIndex::kExgChroma ? sum < 3 * kDarkLevel : sum == 0) {
      return kExgZeroLevel;
    }
    return static_cast<std::uint8_t>(divide_by_twice(510 * g + sum, sum));
  } else if constexpr (kIndex == VegetationIndex::kExgRaw) {
    return static_cast<std::uint8_t>((2 * g - r - b + 512) >> 2);
  } else if constexpr (kIndex == VegetationIndex::kExgMinusExr) {
    const int sum = r + g + b;
    if (sum == 0) return kExgExrGreyLevel;
    return static_cast<std::uint8_t>(
        divide_by_108_times(static_cast<std::uint64_t>(510 * (54 * g + 14 * b) + 54 * sum), sum));
  } else if constexpr (kIndex == VegetationIndex::kCive) {
    return static_cast<std::uint8_t>((kCiveOffset + 52 * g - 28 * r - 25 * b) >> 7);
  } else if constexpr (kIndex == VegetationIndex::kMaxValue) {
    return static_cast<std::uint8_t>(std::max({r, g, b}));
  } else {
    return weighted_gray(static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                         static_cast<std::uint8_t>(b));
  }
}

template <VegetationIndex kIndex>
void packed_rows(const ImageView& frame, PixelRect rect, std::uint8_t* out, std::size_t out_stride,
                 Histogram& histogram) {
  const int red_offset = frame.format == PixelFormat::kBgr24 ? 2 : 0;
  const int blue_offset = 2 - red_offset;
  for (int y = 0; y < rect.height; ++y) {
    const std::uint8_t* in = frame.data + (rect.y + y) * frame.stride + rect.x * 3;
    std::uint8_t* row_out = out + y * out_stride;
    for (int x = 0; x < rect.width; ++x, in += 3) {
      const std::uint8_t value = pixel_index<kIndex>(in[red_offset], in[1], in[blue_offset]);
      row_out[x] = value;
      ++histogram[value];
    }
  }
}

// BT.601 limited-range YUV -> RGB in integers (the V4L2 YUYV convention).
struct Rgb {
  int r, g, b;
};
inline Rgb yuv_to_rgb(int y, int u, int v) {
  const int c = 298 * (y - 16);
  const int d = u - 128;
  const int e = v - 128;
  return {std::clamp((c + 409 * e + 128) >> 8, 0, 255),
          std::clamp((c - 100 * d - 208 * e + 128) >> 8, 0, 255),
          std::clamp((c + 516 * d + 128) >> 8, 0, 255)};
}

template <VegetationIndex kIndex>
void yuyv_rows(const ImageView& frame, PixelRect rect, std::uint8_t* out, std::size_t out_stride,
               Histogram& histogram) {
  for (int y = 0; y < rect.height; ++y) {
    const std::uint8_t* in = frame.data + (rect.y + y) * frame.stride + rect.x * 2;
    std::uint8_t* row_out = out + y * out_stride;
    for (int x = 0; x + 1 < rect.width; x += 2, in += 4) {
      std::uint8_t first, second;
      if constexpr (kIndex == VegetationIndex::kWeightedGray || kIndex == VegetationIndex::kMono) {
        // Luma is the weighted gray: no conversion at all.
        first = in[0];
        second = in[2];
      } else if constexpr (kIndex == VegetationIndex::kCive) {
        // Linear in Y, U, V: no RGB conversion (vegetation_index.hpp).
        first = cive_of_yuv(in[0], in[1], in[3]);
        second = cive_of_yuv(in[2], in[1], in[3]);
      } else {
        const Rgb p0 = yuv_to_rgb(in[0], in[1], in[3]);
        const Rgb p1 = yuv_to_rgb(in[2], in[1], in[3]);
        first = pixel_index<kIndex>(p0.r, p0.g, p0.b);
        second = pixel_index<kIndex>(p1.r, p1.g, p1.b);
      }
      row_out[x] = first;
      row_out[x + 1] = second;
      ++histogram[first];
      ++histogram[second];
    }
  }
}

template <template <VegetationIndex> class Kernel, typename... Args>
void dispatch(VegetationIndex index, Args&&... args) {
  switch (index) {
    case VegetationIndex::kExgNormalized:
      return Kernel<VegetationIndex::kExgNormalized>::run(args...);
    case VegetationIndex::kExgRaw:
      return Kernel<VegetationIndex::kExgRaw>::run(args...);
    case VegetationIndex::kExgMinusExr:
      return Kernel<VegetationIndex::kExgMinusExr>::run(args...);
    case VegetationIndex::kCive:
      return Kernel<VegetationIndex::kCive>::run(args...);
    case VegetationIndex::kMaxValue:
      return Kernel<VegetationIndex::kMaxValue>::run(args...);
    case VegetationIndex::kWeightedGray:
      return Kernel<VegetationIndex::kWeightedGray>::run(args...);
    case VegetationIndex::kMono:
      return Kernel<VegetationIndex::kMono>::run(args...);
    case VegetationIndex::kExgChroma:
      return Kernel<VegetationIndex::kExgChroma>::run(args...);
  }
}

template <VegetationIndex kIndex>
struct PackedKernel {
  static void run(const ImageView& frame, PixelRect rect, std::uint8_t* out, std::size_t out_stride,
                  Histogram& histogram) {
    if constexpr (kIndex == VegetationIndex::kCive) {
      cive_rows_simd(frame, rect, out, out_stride, histogram);
    } else if constexpr (kIndex == VegetationIndex::kExgRaw) {
      exg_raw_rows_simd(frame, rect, out, out_stride, histogram);
    } else {
      packed_rows<kIndex>(frame, rect, out, out_stride, histogram);
    }
  }
};

template <VegetationIndex kIndex>
struct YuyvKernel {
  static void run(const ImageView& frame, PixelRect rect, std::uint8_t* out, std::size_t out_stride,
                  Histogram& histogram) {
    if constexpr (kIndex == VegetationIndex::kCive) {
      cive_yuyv_rows_simd(frame, rect, out, out_stride, histogram);
    } else {
      yuyv_rows<kIndex>(frame, rect, out, out_stride, histogram);
    }
  }
};

}  // namespace

void index_rows_grey(const ImageView& frame, PixelRect rect, std::uint8_t* out,
                     std::size_t out_stride, Histogram& histogram) {
  for (int y = 0; y < rect.height; ++y) {
    const std::uint8_t* in = frame.data + (rect.y + y) * frame.stride + rect.x;
    std::copy(in, in + rect.width, out + y * out_stride);
    for (int x = 0; x < rect.width; ++x) ++histogram[in[x]];
  }
}

void index_rows_yuyv(const ImageView& frame, VegetationIndex index, PixelRect rect,
                     std::uint8_t* out, std::size_t out_stride, Histogram& histogram) {
  dispatch<YuyvKernel>(index, frame, rect, out, out_stride, histogram);
}

void index_rows_packed_rgb(const ImageView& frame, VegetationIndex index, PixelRect rect,
                           std::uint8_t* out, std::size_t out_stride, Histogram& histogram) {
  dispatch<PackedKernel>(index, frame, rect, out, out_stride, histogram);
}

}  // namespace weedspray::vision
