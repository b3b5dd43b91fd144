// SPDX-License-Identifier: Apache-2.0
#include "vision/overlay.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "allocation_counter.hpp"
#include "test_images.hpp"
#include "vision/pipeline.hpp"
#include "vision/weed_source.hpp"

namespace weedspray::vision {
namespace {

using test::BgrFrame;

constexpr int kWidth = 240;
constexpr int kHeight = 120;

// A class map at the region's size: soil, with a weed block and a crop block.
struct ClassMap {
  int width, height;
  std::vector<std::uint8_t> bytes;
  ClassMap(int w, int h)
      : width(w), height(h), bytes(static_cast<std::size_t>(w) * h, kClassSoil) {}
  void fill(int x0, int y0, int x1, int y1, std::uint8_t value) {
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) bytes[static_cast<std::size_t>(y) * width + x] = value;
  }
  ImageView view() const {
    return {bytes.data(), width, height, static_cast<std::size_t>(width), PixelFormat::kGrey};
  }
};

const std::vector<double> kDensities = {0.0, 0.25, 0.5, 0.75};
const std::vector<double> kDuties = {0.0, 40.0, 60.0, 100.0};

BgrImage draw(const BgrFrame& frame, const ClassMap& classes, const PixelRect& region,
              std::span<const double> duties = kDuties) {
  return draw_overlay(frame.view(), classes.view(), region, {1, 4, kDensities, duties});
}

TEST(Overlay, WeedAndCropPixelsHaveTheirColoursAndSoilIsDimmed) {
  const BgrFrame frame(kWidth, kHeight, test::kSoil);
  ClassMap classes(kWidth, kHeight);
  classes.fill(70, 60, 110, 110, kClassWeed);   // zone 1, below its text
  classes.fill(130, 60, 170, 110, kClassCrop);  // zone 2
  const BgrImage out = draw(frame, classes, {0, 0, kWidth, kHeight});
  ASSERT_EQ(out.width, kWidth);
  ASSERT_EQ(out.height, kHeight);
  ASSERT_EQ(out.pixels.size(), static_cast<std::size_t>(kWidth) * kHeight * 3);
  for (int y = 62; y < 108; y += 5) {
    for (int x = 72; x < 108; x += 5) EXPECT_EQ(out.at(x, y), kOverlayWeed) << x << "," << y;
    for (int x = 132; x < 168; x += 5) EXPECT_EQ(out.at(x, y), kOverlayCrop) << x << "," << y;
  }
  // Soil: the frame at 60 % (70, 100, 130 -> 42, 60, 78).
  EXPECT_EQ(out.at(30, 100), (OverlayColour{42, 60, 78}));
  EXPECT_EQ(out.at(200, 100), (OverlayColour{42, 60, 78}));
}

TEST(Overlay, GridLinesLieOnTheZoneBordersOnly) {
  const BgrFrame frame(kWidth, kHeight, test::kSoil);
  const ClassMap classes(kWidth, kHeight);
  const BgrImage out = draw(frame, classes, {0, 0, kWidth, kHeight});
  // Zone c spans columns [60 c, 60 (c + 1)): its rectangle's left edge is at 60 c and its right
  // edge at 60 (c + 1) - 1; the top and bottom rows are borders too.
  for (int y = 70; y < kHeight - 1; y += 7) {
    for (int c = 0; c < 4; ++c) {
      EXPECT_EQ(out.at(60 * c, y), kOverlayGrid) << "left border of zone " << c << " at y " << y;
      EXPECT_EQ(out.at(60 * c + 59, y), kOverlayGrid) << "right border of zone " << c;
      EXPECT_NE(out.at(60 * c + 30, y), kOverlayGrid) << "middle of zone " << c;
    }
  }
  EXPECT_EQ(out.at(100, 0), kOverlayGrid);
  EXPECT_EQ(out.at(100, kHeight - 1), kOverlayGrid);
}

TEST(Overlay, TheRegionOfInterestIsOverlaidAndTheRestLeftAsItWas) {
  const BgrFrame frame(kWidth, kHeight, test::kSoil);
  const PixelRect region{40, 20, 160, 80};
  ClassMap classes(region.width, region.height);
  classes.fill(0, 0, region.width, region.height, kClassWeed);
  const BgrImage out = draw(frame, classes, region);
  EXPECT_EQ(out.at(10, 10), (OverlayColour{70, 100, 130})) << "outside the region: untouched";
  EXPECT_EQ(out.at(230, 110), (OverlayColour{70, 100, 130}));
  EXPECT_EQ(out.at(40, 60), kOverlayGrid) << "the grid starts at the region's left edge";
  EXPECT_EQ(out.at(40 + 40, 60), kOverlayGrid) << "zone border at 160 / 4 into the region";
  EXPECT_EQ(out.at(60, 90), kOverlayWeed);
}

TEST(Overlay, AClassMapAtAnotherResolutionIsScaledToTheRegion) {
  const BgrFrame frame(kWidth, kHeight, test::kSoil);
  ClassMap classes(4, 2);                // a network's output: one cell per zone and half height
  classes.fill(2, 1, 3, 2, kClassWeed);  // zone 2, bottom half
  const BgrImage out = draw(frame, classes, {0, 0, kWidth, kHeight});
  EXPECT_EQ(out.at(150, 100), kOverlayWeed);
  EXPECT_EQ(out.at(150, 61), kOverlayWeed);
  EXPECT_NE(out.at(150, 58), kOverlayWeed) << "top half of the zone is soil";
  EXPECT_NE(out.at(90, 100), kOverlayWeed) << "zone 1 is soil";
}

TEST(Overlay, DensityAndDutyAreWrittenInTheirZone) {
  const BgrFrame frame(kWidth, kHeight, test::kSoil);
  const ClassMap classes(kWidth, kHeight);
  const BgrImage with_duties = draw(frame, classes, {0, 0, kWidth, kHeight});
  const BgrImage without = draw(frame, classes, {0, 0, kWidth, kHeight}, {});
  std::vector<double> other_duties = kDuties;
  other_duties[2] = 7.0;
  const BgrImage other = draw_overlay(frame.view(), classes.view(), {0, 0, kWidth, kHeight},
                                      {1, 4, kDensities, other_duties});
  const auto differs_in = [](const BgrImage& a, const BgrImage& b, int x0, int x1) {
    int n = 0;
    for (int y = 0; y < a.height; ++y)
      for (int x = x0; x < x1; ++x) n += !(a.at(x, y) == b.at(x, y));
    return n;
  };
  EXPECT_GT(differs_in(with_duties, without, 0, kWidth), 0) << "no duty text drawn";
  // Zone 2's duty changed: its text changes, the other zones stay as they were.
  EXPECT_GT(differs_in(with_duties, other, 121, 179), 0);
  EXPECT_EQ(differs_in(with_duties, other, 0, 119), 0);
  EXPECT_EQ(differs_in(with_duties, other, 181, kWidth), 0);
  // Text is drawn white on a dark outline.
  bool white = false;
  for (int y = 0; y < 60 && !white; ++y)
    for (int x = 0; x < kWidth && !white; ++x)
      white = with_duties.at(x, y) == OverlayColour{255, 255, 255};
  EXPECT_TRUE(white);
}

TEST(Overlay, InputsThatDoNotFitAreRefused) {
  const BgrFrame frame(kWidth, kHeight, test::kSoil);
  const ClassMap classes(kWidth, kHeight);
  EXPECT_THROW(draw(frame, classes, {100, 0, kWidth, kHeight}), std::invalid_argument);
  const std::vector<double> two = {0.1, 0.2};
  EXPECT_THROW(draw_overlay(frame.view(), classes.view(), {0, 0, kWidth, kHeight}, {1, 4, two, {}}),
               std::invalid_argument);
  EXPECT_THROW(
      draw_overlay(frame.view(), ImageView{}, {0, 0, kWidth, kHeight}, {1, 4, kDensities, {}}),
      std::invalid_argument);
}

TEST(Overlay, OtherPixelFormatsComeOutAsBgr) {
  // RGB: the same soil colour stored R G B comes out B G R (dimmed).
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(kWidth) * kHeight * 3);
  for (std::size_t i = 0; i < rgb.size(); i += 3) {
    rgb[i] = 130;
    rgb[i + 1] = 100;
    rgb[i + 2] = 70;
  }
  const ClassMap classes(kWidth, kHeight);
  const ImageView view{rgb.data(), kWidth, kHeight, static_cast<std::size_t>(kWidth) * 3,
                       PixelFormat::kRgb24};
  const BgrImage out =
      draw_overlay(view, classes.view(), {0, 0, kWidth, kHeight}, {1, 4, kDensities, {}});
  EXPECT_EQ(out.at(30, 100), (OverlayColour{42, 60, 78}));
}

TEST(Overlay, YuyvAndGreyFramesComeOutAsBgr) {
  // YUYV (V4L2 cameras): Y 100 with neutral chroma is grey 100 -> 60 dimmed, at full size.
  std::vector<std::uint8_t> yuyv(static_cast<std::size_t>(kWidth) * kHeight * 2);
  for (std::size_t i = 0; i < yuyv.size(); i += 2) {
    yuyv[i] = 100;
    yuyv[i + 1] = 128;
  }
  const ClassMap classes(kWidth, kHeight);
  const ImageView yuyv_view{yuyv.data(), kWidth, kHeight, static_cast<std::size_t>(kWidth) * 2,
                            PixelFormat::kYuyv};
  const BgrImage out =
      draw_overlay(yuyv_view, classes.view(), {0, 0, kWidth, kHeight}, {1, 4, kDensities, {}});
  ASSERT_EQ(out.width, kWidth);
  ASSERT_EQ(out.height, kHeight);
  const OverlayColour soil = out.at(30, 100);
  EXPECT_EQ(soil.b, soil.g);
  EXPECT_EQ(soil.g, soil.r);
  EXPECT_NEAR(soil.g, 0.6 * 100 * 255 / 219.0 - 0.6 * 16 * 255 / 219.0, 2) << "BT.601 Y 100";
  // Grey (mono industrial cameras).
  const std::vector<std::uint8_t> grey(static_cast<std::size_t>(kWidth) * kHeight, 200);
  const ImageView grey_view{grey.data(), kWidth, kHeight, static_cast<std::size_t>(kWidth),
                            PixelFormat::kGrey};
  EXPECT_EQ(draw_overlay(grey_view, classes.view(), {0, 0, kWidth, kHeight}, {1, 4, kDensities, {}})
                .at(30, 100),
            (OverlayColour{120, 120, 120}));
}

// The pipeline's own class map, written into a caller's buffer without allocating, drawn red
// where the frame is green.
TEST(Overlay, ThePipelinesClassMapMarksItsPlants) {
  BgrFrame frame(kWidth, kHeight, test::kSoil);
  for (int y = 60; y < 110; ++y)
    for (int x = 70; x < 110; ++x) frame.set(x, y, test::kPlant);
  PipelineConfig config = default_pipeline_config();
  Pipeline pipeline(config);
  const FrameResult& result = pipeline.process(frame.view());
  ASSERT_TRUE(pipeline.last_frame_ok());
  std::vector<std::uint8_t> buffer(pipeline.class_map_pixels());
  const long before = weedspray::test::allocation_count();
  const ImageView classes = pipeline.class_map_into(buffer);
  EXPECT_EQ(weedspray::test::allocation_count(), before) << "class_map_into allocated";
  ASSERT_EQ(classes.data, buffer.data());
  EXPECT_EQ(classes.width, kWidth);
  std::vector<std::uint8_t> too_small(buffer.size() - 1);
  EXPECT_EQ(pipeline.class_map_into(too_small).data, nullptr);
  const ImageView own = pipeline.class_map();
  EXPECT_TRUE(std::equal(buffer.begin(), buffer.end(), own.data)) << "class_map() differs";

  const BgrImage out = draw_overlay(frame.view(), classes, pipeline.region(),
                                    {result.rows, result.cols, result.densities(), {}});
  EXPECT_EQ(out.at(90, 100), kOverlayWeed);
  EXPECT_EQ(out.at(200, 100), (OverlayColour{42, 60, 78}));
}

}  // namespace
}  // namespace weedspray::vision
