// SPDX-License-Identifier: Apache-2.0
#include "vision/vegetation_index.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "test_images.hpp"

namespace weedspray::vision {
namespace {

using test::Bgr;
using test::BgrFrame;

TEST(VegetationIndexNames, RoundTripAndRejectUnknown) {
  ASSERT_EQ(all_vegetation_indices().size(), vegetation_index_names().size());
  for (VegetationIndex index : all_vegetation_indices()) {
    EXPECT_EQ(parse_vegetation_index(to_string(index)), index);
  }
  EXPECT_EQ(parse_vegetation_index("exg_norm"), VegetationIndex::kExgNormalized);
  EXPECT_FALSE(parse_vegetation_index("ExG").has_value());
  EXPECT_FALSE(parse_vegetation_index("").has_value());
}

// Hand-computed values on each documented scale.
TEST(VegetationIndexOf, NormalisedExgScale) {
  // Grey: r = g = b = 1/3, ExG = 0 -> 85.
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgNormalized, 90, 90, 90), 85);
  // Pure green: g = 1, ExG = 2 -> 255. Pure red: ExG = -1 -> 0.
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgNormalized, 0, 200, 0), 255);
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgNormalized, 200, 0, 0), 0);
  // R 60, G 150, B 40: 255 * 150 / 250 = 153.
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgNormalized, 60, 150, 40), 153);
  // Black has no colour: ExG 0.
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgNormalized, 0, 0, 0), 85);
  // Dark pixels are "no colour" for exg_chroma only.
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgChroma, 2, 10, 2), 85);
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgNormalized, 2, 10, 2), 182);
}

TEST(VegetationIndexOf, RawExgCiveExgExrAndGreys) {
  // Raw ExG: (2G - R - B + 512) / 4: 2*150 - 60 - 40 = 200 -> 712 / 4 = 178; grey -> 128.
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgRaw, 60, 150, 40), 178);
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgRaw, 77, 77, 77), 128);
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgRaw, 0, 255, 0), 255);
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgRaw, 255, 0, 255), 0);
  // CIVE: (16448 + 52*150 - 28*60 - 25*40) >> 7 = 21568 >> 7 = 168; black 128; white 126.
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kCive, 60, 150, 40), 168);
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kCive, 0, 0, 0), 128);
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kCive, 255, 255, 255), 126);
  // ExG - ExR = 3g - 2.4r - b; grey: 3/3 - 2.4/3 - 1/3 = -0.1333 -> (2.2667)*255/5.4 = 107.
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgMinusExr, 50, 50, 50), 107);
  // Pure green: 3 -> 255.
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kExgMinusExr, 0, 100, 0), 255);
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kMaxValue, 60, 150, 40), 150);
  // Weighted: (77*60 + 150*150 + 29*40 + 128) >> 8 = 28400 >> 8 = 110.
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kWeightedGray, 60, 150, 40), 110);
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kMono, 60, 150, 40), 110);
}

// The frame kernels (SIMD for some indices) must equal the per-pixel reference bit for bit,
// on odd widths (SIMD tail), padded rows and a region offset.
TEST(ComputeVegetationIndex, FrameKernelsMatchPixelReference) {
  std::mt19937 random(7);
  BgrFrame frame(53, 9, Bgr{0, 0, 0}, 5);
  for (int y = 0; y < frame.height; ++y) {
    for (int x = 0; x < frame.width; ++x) {
      frame.set(x, y,
                Bgr{static_cast<std::uint8_t>(random()), static_cast<std::uint8_t>(random()),
                    static_cast<std::uint8_t>(random())});
    }
  }
  // Extremes too: they exercise the fixed-point ranges.
  frame.set(3, 2, Bgr{255, 255, 255});
  frame.set(4, 2, Bgr{255, 0, 255});
  frame.set(5, 2, Bgr{0, 255, 0});
  const PixelRect rect{2, 1, 49, 7};
  for (VegetationIndex index : all_vegetation_indices()) {
    std::vector<std::uint8_t> out(rect.width * rect.height);
    Histogram histogram{};
    compute_vegetation_index(frame.view(), index, rect, out.data(), rect.width, histogram);
    Histogram expected_histogram{};
    for (int y = 0; y < rect.height; ++y) {
      for (int x = 0; x < rect.width; ++x) {
        const std::uint8_t* p = &frame.bytes[(rect.y + y) * frame.stride + (rect.x + x) * 3];
        const std::uint8_t expected = vegetation_index_of(index, p[2], p[1], p[0]);
        ASSERT_EQ(out[y * rect.width + x], expected) << to_string(index) << " at " << x << "," << y;
        ++expected_histogram[expected];
      }
    }
    EXPECT_EQ(histogram, expected_histogram) << to_string(index);
  }
}

TEST(ComputeVegetationIndex, RgbOrderGivesTheSameIndexAsBgr) {
  BgrFrame bgr(20, 2, Bgr{40, 150, 60});
  bgr.set(7, 1, Bgr{10, 20, 200});
  std::vector<std::uint8_t> rgb_bytes(bgr.bytes);
  for (std::size_t i = 0; i + 2 < rgb_bytes.size(); i += 3)
    std::swap(rgb_bytes[i], rgb_bytes[i + 2]);
  const ImageView rgb{rgb_bytes.data(), 20, 2, bgr.stride, PixelFormat::kRgb24};
  for (VegetationIndex index : all_vegetation_indices()) {
    std::vector<std::uint8_t> a(40), b(40);
    Histogram ha{}, hb{};
    compute_vegetation_index(bgr.view(), index, {0, 0, 20, 2}, a.data(), 20, ha);
    compute_vegetation_index(rgb, index, {0, 0, 20, 2}, b.data(), 20, hb);
    EXPECT_EQ(a, b) << to_string(index);
  }
}

TEST(ComputeVegetationIndex, GreyFramesPassThroughForEveryIndex) {
  const std::vector<std::uint8_t> grey = {0, 17, 128, 255, 3, 4, 5, 6};
  const ImageView view{grey.data(), 4, 2, 4, PixelFormat::kGrey};
  for (VegetationIndex index : all_vegetation_indices()) {
    std::vector<std::uint8_t> out(8);
    Histogram histogram{};
    compute_vegetation_index(view, index, {0, 0, 4, 2}, out.data(), 4, histogram);
    EXPECT_EQ(out, grey) << to_string(index);
    EXPECT_EQ(histogram[17], 1u);
    EXPECT_EQ(histogram_total(histogram), 8u);
  }
}

TEST(ComputeVegetationIndex, YuyvUsesLumaForGreysAndConvertsForColourIndices) {
  // Two pixel pairs: Y0 U Y1 V. Grey (U = V = 128) Y = 16 + 219 * k/255 maps to RGB k.
  // Pair 1: Y = 126 (RGB 128 grey) twice; pair 2: a green YUV (Y 145, U 54, V 34).
  const std::vector<std::uint8_t> yuyv = {126, 128, 126, 128, 145, 54, 145, 34};
  const ImageView view{yuyv.data(), 4, 1, 8, PixelFormat::kYuyv};
  std::vector<std::uint8_t> out(4);
  Histogram histogram{};
  compute_vegetation_index(view, VegetationIndex::kWeightedGray, {0, 0, 4, 1}, out.data(), 4,
                           histogram);
  EXPECT_EQ(out, (std::vector<std::uint8_t>{126, 126, 145, 145}));
  histogram = {};
  compute_vegetation_index(view, VegetationIndex::kExgNormalized, {0, 0, 4, 1}, out.data(), 4,
                           histogram);
  // Grey pair: ExG 0 -> 85 (BT.601 limited range: Y 126 -> R = G = B = 128).
  EXPECT_EQ(out[0], 85);
  EXPECT_EQ(out[1], 85);
  // Green pair: R = (298*129 + 409*-94 + 128) >> 8 = 0 (clamped), G = (38442 + 7400 + 19552 +
  // 128) >> 8 = 255 (clamped), B = (38442 - 38184 + 128) >> 8 = 1 -> 255 * 255 / 256 = 254.
  EXPECT_EQ(out[2], 254);
  EXPECT_EQ(histogram[85], 2u);
}

TEST(DefaultFixedThreshold, SitsBetweenSoilAndPlantOnEachColourScale) {
  for (VegetationIndex index :
       {VegetationIndex::kExgNormalized, VegetationIndex::kExgRaw, VegetationIndex::kExgMinusExr,
        VegetationIndex::kCive, VegetationIndex::kExgChroma}) {
    const int level = default_fixed_threshold(index);
    EXPECT_LT(vegetation_index_of(index, test::kSoil.r, test::kSoil.g, test::kSoil.b), level)
        << to_string(index);
    EXPECT_GT(vegetation_index_of(index, test::kPlant.r, test::kPlant.g, test::kPlant.b), level)
        << to_string(index);
  }
}

}  // namespace
}  // namespace weedspray::vision

namespace weedspray::vision {
namespace {

// Normalised ExG depends on G and R + G + B only: one pixel per (G, R + B) pair covers every
// division the reciprocal table replaces.
TEST(ComputeVegetationIndex, NormalisedExgExactForEveryGreenAndSum) {
  const int width = 511;  // R + B = 0..510
  test::BgrFrame frame(width, 256, test::kBlack);
  for (int g = 0; g < 256; ++g) {
    for (int rb = 0; rb < width; ++rb) {
      const int r = std::min(rb, 255);
      frame.set(rb, g,
                {static_cast<std::uint8_t>(rb - r), static_cast<std::uint8_t>(g),
                 static_cast<std::uint8_t>(r)});
    }
  }
  for (VegetationIndex index : {VegetationIndex::kExgNormalized, VegetationIndex::kExgChroma}) {
    std::vector<std::uint8_t> out(width * 256);
    Histogram histogram{};
    compute_vegetation_index(frame.view(), index, {0, 0, width, 256}, out.data(), width, histogram);
    for (int g = 0; g < 256; ++g) {
      for (int rb = 0; rb < width; ++rb) {
        const int r = std::min(rb, 255);
        ASSERT_EQ(out[g * width + rb], vegetation_index_of(index, static_cast<std::uint8_t>(r),
                                                           static_cast<std::uint8_t>(g),
                                                           static_cast<std::uint8_t>(rb - r)))
            << to_string(index) << " G " << g << " R+B " << rb;
      }
    }
  }
}

}  // namespace
}  // namespace weedspray::vision

namespace weedspray::vision {
namespace {

TEST(CiveOfYuv, HandComputedAndClamped) {
  // Grey Y 126 (RGB 128): 36670 - 126 - 9088 - 11136 = 16320 -> 127, as cive of RGB 128.
  EXPECT_EQ(cive_of_yuv(126, 128, 128), 127);
  EXPECT_EQ(vegetation_index_of(VegetationIndex::kCive, 128, 128, 128), 127);
  // Green Y 145 U 54 V 34: 36670 - 145 - 3834 - 2958 = 29733 -> 232.
  EXPECT_EQ(cive_of_yuv(145, 54, 34), 232);
  EXPECT_EQ(cive_of_yuv(255, 255, 255), 0);  // below zero: clamped
  EXPECT_EQ(cive_of_yuv(0, 0, 0), 255);      // 286: capped
}

// In-gamut colours: CIVE from YUV agrees with CIVE from the RGB they encode.
TEST(CiveOfYuv, AgreesWithRgbCiveInGamut) {
  std::mt19937 random(3);
  for (int i = 0; i < 20000; ++i) {
    const int r = random() % 256, g = random() % 256, b = random() % 256;
    // BT.601 limited-range RGB -> YUV in 8-bit fixed point.
    const int y = ((66 * r + 129 * g + 25 * b + 128) >> 8) + 16;
    const int u = ((-38 * r - 74 * g + 112 * b + 128) >> 8) + 128;
    const int v = ((112 * r - 94 * g - 18 * b + 128) >> 8) + 128;
    const int from_rgb = vegetation_index_of(VegetationIndex::kCive, r, g, b);
    const int from_yuv = cive_of_yuv(y, u, v);
    ASSERT_NEAR(from_yuv, from_rgb, 2) << r << "," << g << "," << b;
  }
}

TEST(ComputeVegetationIndex, YuyvCiveKernelMatchesPixelReference) {
  std::mt19937 random(11);
  const int width = 70, height = 5;  // odd number of 16-pixel blocks plus a tail
  const std::size_t stride = width * 2 + 6;
  std::vector<std::uint8_t> yuyv(stride * height);
  for (auto& byte : yuyv) byte = static_cast<std::uint8_t>(random());
  const ImageView view{yuyv.data(), width, height, stride, PixelFormat::kYuyv};
  const PixelRect rect{2, 1, 66, 4};
  std::vector<std::uint8_t> out(rect.width * rect.height);
  Histogram histogram{};
  compute_vegetation_index(view, VegetationIndex::kCive, rect, out.data(), rect.width, histogram);
  Histogram expected_histogram{};
  for (int y = 0; y < rect.height; ++y) {
    for (int x = 0; x < rect.width; ++x) {
      const std::uint8_t* pair = &yuyv[(rect.y + y) * stride + ((rect.x + x) & ~1) * 2];
      const std::uint8_t expected = cive_of_yuv(pair[(x & 1) * 2], pair[1], pair[3]);
      ASSERT_EQ(out[y * rect.width + x], expected) << x << "," << y;
      ++expected_histogram[expected];
    }
  }
  EXPECT_EQ(histogram, expected_histogram);
}

}  // namespace
}  // namespace weedspray::vision

namespace weedspray::vision {
namespace {

// ExG - ExR depends on G, B and R + G + B: every (R, G, B) once, against the reference.
TEST(ComputeVegetationIndex, ExgMinusExrExactForEveryColour) {
  test::BgrFrame frame(256, 256, test::kBlack);
  std::vector<std::uint8_t> out(256 * 256);
  for (int g = 0; g < 256; ++g) {
    for (int r = 0; r < 256; ++r) {
      for (int b = 0; b < 256; ++b) {
        frame.set(b, r,
                  {static_cast<std::uint8_t>(b), static_cast<std::uint8_t>(g),
                   static_cast<std::uint8_t>(r)});
      }
    }
    Histogram histogram{};
    compute_vegetation_index(frame.view(), VegetationIndex::kExgMinusExr, {0, 0, 256, 256},
                             out.data(), 256, histogram);
    for (int r = 0; r < 256; ++r) {
      for (int b = 0; b < 256; ++b) {
        ASSERT_EQ(out[r * 256 + b],
                  vegetation_index_of(VegetationIndex::kExgMinusExr, static_cast<std::uint8_t>(r),
                                      static_cast<std::uint8_t>(g), static_cast<std::uint8_t>(b)))
            << r << "," << g << "," << b;
      }
    }
  }
}

}  // namespace
}  // namespace weedspray::vision
