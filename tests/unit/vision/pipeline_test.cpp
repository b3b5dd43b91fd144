// SPDX-License-Identifier: Apache-2.0
#include "vision/pipeline.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

#include "allocation_counter.hpp"
#include "test_images.hpp"

namespace weedspray::vision {
namespace {

using test::BgrFrame;

TEST(PipelineConfig, DefaultIsValidAndNamed) {
  const PipelineConfig config = default_pipeline_config();
  EXPECT_NO_THROW(validate(config));
  EXPECT_EQ(config.index, VegetationIndex::kCive);
  EXPECT_EQ(config.threshold, ThresholdMethod::kOtsu);
}

TEST(PipelineConfig, BadFieldsAreNamed) {
  PipelineConfig config = default_pipeline_config();
  config.rows = 0;
  EXPECT_THROW(
      {
        try {
          Pipeline pipeline(config);
        } catch (const std::invalid_argument& error) {
          EXPECT_NE(std::string(error.what()).find("rows"), std::string::npos);
          throw;
        }
      },
      std::invalid_argument);
  config = default_pipeline_config();
  config.rows = 9;
  config.cols = 8;  // 72 zones > kMaxZones
  EXPECT_THROW(validate(config), std::invalid_argument);
  config = default_pipeline_config();
  config.roi.left = 0.6;
  config.roi.right = 0.4;
  EXPECT_THROW(validate(config), std::invalid_argument);
  config = default_pipeline_config();
  config.level_cuts.upper = {0.5, 0.4, 0.6, 0.7, 0.8};
  EXPECT_THROW(validate(config), std::invalid_argument);
}

// 40x20 soil frame; zone (0,0) of a 2x4 grid (10x10 px) fully green, zone (1,3) a quarter.
TEST(Pipeline, ZoneDensitiesOnAKnownFrame) {
  BgrFrame frame(40, 20, test::kSoil);
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 10; ++x) frame.set(x, y, test::kPlant);
  }
  for (int y = 10; y < 15; ++y) {
    for (int x = 30; x < 35; ++x) frame.set(x, y, test::kPlant);
  }
  PipelineConfig config = default_pipeline_config();
  config.rows = 2;
  config.cols = 4;
  Pipeline pipeline(config);
  const FrameResult& result = pipeline.process(frame.view());
  ASSERT_TRUE(pipeline.last_frame_ok());
  EXPECT_TRUE(result.bimodal);
  EXPECT_GE(result.threshold, 127);  // soil level
  EXPECT_LT(result.threshold, 168);  // plant level
  ASSERT_EQ(result.densities().size(), 8u);
  EXPECT_DOUBLE_EQ(result.density(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(result.density(1, 3), 0.25);
  EXPECT_DOUBLE_EQ(result.density(0, 1), 0.0);
  EXPECT_EQ(result.zone_level[0], DensityLevel::kVerySevere);
  EXPECT_EQ(result.zone_level[1], DensityLevel::kNone);
  EXPECT_DOUBLE_EQ(result.vegetation_fraction, 125.0 / 800.0);
}

TEST(Pipeline, RegionOfInterestRestrictsTheZones) {
  BgrFrame frame(40, 20, test::kSoil);
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 20; ++x) frame.set(x, y, test::kPlant);  // left half green
  }
  PipelineConfig config = default_pipeline_config();
  config.rows = 1;
  config.cols = 2;
  config.roi = {0.25, 0.5, 0.75, 1.0};  // x 10..30, y 10..20
  Pipeline pipeline(config);
  const FrameResult& result = pipeline.process(frame.view());
  EXPECT_EQ(pipeline.region().x, 10);
  EXPECT_EQ(pipeline.region().width, 20);
  EXPECT_EQ(pipeline.region().height, 10);
  EXPECT_DOUBLE_EQ(result.density(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(result.density(0, 1), 0.0);
}

// A soil greener than CIVE's fixed level (131), as another camera may see it: the default
// pipeline judges the frame by its own soil peak and finds no plant; the fixed scale would
// call most of the soil plant.
TEST(Pipeline, DefaultJudgesAUnimodalFrameByItsOwnSoilPeak) {
  constexpr test::Bgr kSoil131{60, 91, 100};  // CIVE levels 131, 132, 133
  constexpr test::Bgr kSoil132{60, 93, 100};
  constexpr test::Bgr kSoil133{60, 95, 100};
  BgrFrame frame(40, 20, kSoil132);
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 40; x += 4) frame.set(x, y, y % 2 ? kSoil131 : kSoil133);
  }
  PipelineConfig config = default_pipeline_config();
  config.cols = 1;
  Pipeline pipeline(config);
  const FrameResult& result = pipeline.process(frame.view());
  ASSERT_TRUE(pipeline.last_frame_ok());
  EXPECT_FALSE(result.bimodal);
  EXPECT_EQ(histogram_peak(pipeline.histogram()), 132);
  EXPECT_EQ(result.threshold, 132 + config.threshold_params.peak_margin);
  EXPECT_DOUBLE_EQ(result.vegetation_fraction, 0.0);

  config.threshold_params.unimodal = UnimodalPolicy::kFixedScale;
  Pipeline fixed_scale(config);
  EXPECT_EQ(fixed_scale.process(frame.view()).threshold, 131);
  EXPECT_DOUBLE_EQ(fixed_scale.process(frame.view()).vegetation_fraction, 0.875);  // all but 131
}

// Degenerate frames through the whole pipeline, with every index and threshold method.
TEST(Pipeline, DegenerateFramesGiveSaneDensities) {
  struct Case {
    const char* name;
    test::Bgr colour;
    double expected_fraction;
  };
  const Case cases[] = {{"bare soil", test::kSoil, 0.0},
                        {"full canopy", test::kPlant, 1.0},
                        {"black", test::kBlack, 0.0},
                        {"saturated", test::kWhite, 0.0}};
  for (const Case& c : cases) {
    BgrFrame frame(64, 32, c.colour);
    if (c.colour.g == test::kSoil.g) {
      // Real bare soil is noisy: +-2 levels of texture.
      for (int y = 0; y < 32; ++y) {
        for (int x = 0; x < 64; ++x) {
          const int d = (x * 7 + y * 13) % 5 - 2;
          frame.set(
              x, y,
              {static_cast<std::uint8_t>(c.colour.b + d), static_cast<std::uint8_t>(c.colour.g + d),
               static_cast<std::uint8_t>(c.colour.r - d)});
        }
      }
    }
    for (VegetationIndex index : {VegetationIndex::kExgNormalized, VegetationIndex::kExgRaw,
                                  VegetationIndex::kCive, VegetationIndex::kExgMinusExr}) {
      for (ThresholdMethod method : all_threshold_methods()) {
        PipelineConfig config = default_pipeline_config();
        config.index = index;
        config.threshold = method;
        Pipeline pipeline(config);
        const FrameResult& result = pipeline.process(frame.view());
        EXPECT_FALSE(result.bimodal)
            << c.name << " " << to_string(index) << " " << to_string(method);
        EXPECT_DOUBLE_EQ(result.vegetation_fraction, c.expected_fraction)
            << c.name << " " << to_string(index) << " " << to_string(method);
      }
    }
  }
}

TEST(Pipeline, MalformedFramesAreRejectedWithoutCrashing) {
  Pipeline pipeline(default_pipeline_config());
  EXPECT_EQ(pipeline.process(ImageView{}).vegetation_fraction, 0.0);
  EXPECT_FALSE(pipeline.last_frame_ok());
  BgrFrame frame(8, 8, test::kPlant);
  ImageView short_stride = frame.view();
  short_stride.stride = 10;  // < 8 * 3
  pipeline.process(short_stride);
  EXPECT_FALSE(pipeline.last_frame_ok());
  PipelineConfig config = default_pipeline_config();
  config.cols = 16;  // more zones than the 8 columns
  Pipeline narrow(config);
  narrow.process(frame.view());
  EXPECT_FALSE(narrow.last_frame_ok());
}

TEST(Pipeline, NoAllocationOnceWarmedUp) {
  BgrFrame frame(320, 200, test::kSoil);
  for (int y = 50; y < 120; ++y) {
    for (int x = 30; x < 200; ++x) frame.set(x, y, test::kPlant);
  }
  for (ThresholdMethod method : all_threshold_methods()) {
    PipelineConfig config = default_pipeline_config();
    config.threshold = method;
    config.inter_row_map = true;
    Pipeline pipeline(config);
    pipeline.process(frame.view());  // warm-up: sizes the buffers
    const long before = weedspray::test::allocation_count();
    for (int i = 0; i < 5; ++i) pipeline.process(frame.view());
    EXPECT_EQ(weedspray::test::allocation_count(), before) << to_string(method);
  }
}

TEST(Pipeline, GreyAndYuyvFramesAreAccepted) {
  std::vector<std::uint8_t> grey(32 * 16, 40);
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 8; ++x) grey[y * 32 + x] = 200;  // bright quarter
  }
  PipelineConfig config = default_pipeline_config();
  config.index = VegetationIndex::kMono;
  config.cols = 4;
  Pipeline pipeline(config);
  const FrameResult& result = pipeline.process({grey.data(), 32, 16, 32, PixelFormat::kGrey});
  ASSERT_TRUE(pipeline.last_frame_ok());
  EXPECT_TRUE(result.bimodal);
  EXPECT_DOUBLE_EQ(result.density(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(result.density(0, 1), 0.0);

  // YUYV: left half green (Y 145 U 54 V 34), right half grey (Y 126 U 128 V 128).
  std::vector<std::uint8_t> yuyv;
  for (int y = 0; y < 4; ++y) {
    for (int pair = 0; pair < 8; ++pair) {
      const bool green = pair < 4;
      yuyv.insert(yuyv.end(), {static_cast<std::uint8_t>(green ? 145 : 126),
                               static_cast<std::uint8_t>(green ? 54 : 128),
                               static_cast<std::uint8_t>(green ? 145 : 126),
                               static_cast<std::uint8_t>(green ? 34 : 128)});
    }
  }
  Pipeline colour(default_pipeline_config());
  const FrameResult& yuyv_result = colour.process({yuyv.data(), 16, 4, 32, PixelFormat::kYuyv});
  ASSERT_TRUE(colour.last_frame_ok());
  EXPECT_DOUBLE_EQ(yuyv_result.density(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(yuyv_result.density(0, 3), 0.0);
}

}  // namespace
}  // namespace weedspray::vision
