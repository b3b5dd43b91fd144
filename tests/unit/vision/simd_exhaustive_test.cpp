// SPDX-License-Identifier: Apache-2.0
// The SIMD kernels of vision/linear_index_simd.cpp (OpenCV universal intrinsics: SSE2 on x86-64,
// NEON on aarch64) against the per-pixel reference on every input they can meet: all 2^24
// RGB colours for cive and exg_raw, all 2^24 (Y, U, V) for cive straight from YUYV. The arm64
// preset runs this binary under qemu-aarch64, so there it checks the NEON code bit for bit.
#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/core/hal/intrin.hpp>
#include <vector>

#include "vision/vegetation_index.hpp"

namespace weedspray::vision {
namespace {

// Which backend OpenCV's universal intrinsics compile to here: the same headers and flags as
// vision/linear_index_simd.cpp. Without a native 128-bit backend they fall back to plain C++
// (intrin_cpp.hpp): still correct, but the "SIMD" kernels would be scalar loops.
TEST(SimdBackend, UniversalIntrinsicsAreNativeOnThisTarget) {
#if defined(__aarch64__)
  static_assert(CV_NEON && CV_SIMD128, "aarch64 build without OpenCV's NEON intrinsics");
  EXPECT_TRUE(cv::checkHardwareSupport(CV_CPU_NEON));
#elif defined(__x86_64__)
  static_assert(CV_SSE2 && CV_SIMD128, "x86-64 build without OpenCV's SSE2 intrinsics");
  EXPECT_TRUE(cv::checkHardwareSupport(CV_CPU_SSE2));
#else
  GTEST_SKIP() << "no SIMD backend expected on this architecture";
#endif
}

// One colour per pixel: row = (r, g >> 4), column = (g & 15, b); 256 rows at a time.
TEST(SimdExhaustive, LinearRgbIndicesMatchThePixelReferenceForEveryColour) {
  constexpr int kWidth = 4096;
  constexpr int kRows = 16;  // one red level
  std::vector<std::uint8_t> bgr(kWidth * kRows * 3);
  std::vector<std::uint8_t> out(kWidth * kRows);
  for (VegetationIndex index : {VegetationIndex::kCive, VegetationIndex::kExgRaw}) {
    Histogram histogram{};
    Histogram expected_histogram{};
    std::uint64_t mismatches = 0;
    for (int red = 0; red < 256; ++red) {
      for (int row = 0; row < kRows; ++row) {
        for (int column = 0; column < kWidth; ++column) {
          std::uint8_t* pixel = &bgr[(row * kWidth + column) * 3];
          pixel[0] = static_cast<std::uint8_t>(column & 0xFF);               // blue
          pixel[1] = static_cast<std::uint8_t>((row << 4) | (column >> 8));  // green
          pixel[2] = static_cast<std::uint8_t>(red);                         // red
        }
      }
      const ImageView view{bgr.data(), kWidth, kRows, kWidth * 3, PixelFormat::kBgr24};
      compute_vegetation_index(view, index, {0, 0, kWidth, kRows}, out.data(), kWidth, histogram);
      for (int i = 0; i < kWidth * kRows; ++i) {
        const std::uint8_t* pixel = &bgr[i * 3];
        const std::uint8_t expected = vegetation_index_of(index, pixel[2], pixel[1], pixel[0]);
        ++expected_histogram[expected];
        if (out[i] != expected && ++mismatches <= 5) {
          ADD_FAILURE() << to_string(index) << " rgb " << red << "," << int{pixel[1]} << ","
                        << int{pixel[0]} << ": " << int{out[i]} << " != " << int{expected};
        }
      }
    }
    EXPECT_EQ(mismatches, 0u) << to_string(index);
    EXPECT_EQ(histogram, expected_histogram) << to_string(index);
  }
}

// YUYV: row = (U, V), each row Y0 U Y1 V with Y running 0..255 along it.
TEST(SimdExhaustive, CiveFromYuyvMatchesThePixelReferenceForEveryYuv) {
  constexpr int kWidth = 256;
  constexpr int kRows = 256;  // one U level
  std::vector<std::uint8_t> yuyv(kWidth * kRows * 2);
  std::vector<std::uint8_t> out(kWidth * kRows);
  Histogram histogram{};
  Histogram expected_histogram{};
  std::uint64_t mismatches = 0;
  for (int u = 0; u < 256; ++u) {
    for (int v = 0; v < kRows; ++v) {
      std::uint8_t* row = &yuyv[v * kWidth * 2];
      for (int pair = 0; pair < kWidth / 2; ++pair) {
        row[4 * pair + 0] = static_cast<std::uint8_t>(2 * pair);
        row[4 * pair + 1] = static_cast<std::uint8_t>(u);
        row[4 * pair + 2] = static_cast<std::uint8_t>(2 * pair + 1);
        row[4 * pair + 3] = static_cast<std::uint8_t>(v);
      }
    }
    const ImageView view{yuyv.data(), kWidth, kRows, kWidth * 2, PixelFormat::kYuyv};
    compute_vegetation_index(view, VegetationIndex::kCive, {0, 0, kWidth, kRows}, out.data(),
                             kWidth, histogram);
    for (int v = 0; v < kRows; ++v) {
      for (int y = 0; y < kWidth; ++y) {
        const std::uint8_t expected =
            cive_of_yuv(static_cast<std::uint8_t>(y), static_cast<std::uint8_t>(u),
                        static_cast<std::uint8_t>(v));
        ++expected_histogram[expected];
        const std::uint8_t got = out[v * kWidth + y];
        if (got != expected && ++mismatches <= 5) {
          ADD_FAILURE() << "yuv " << y << "," << u << "," << v << ": " << int{got}
                        << " != " << int{expected};
        }
      }
    }
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_EQ(histogram, expected_histogram);
}

}  // namespace
}  // namespace weedspray::vision
