// SPDX-License-Identifier: Apache-2.0
// dnn, hybrid, plants and dnn_vegetation weed sources with tests/data/tiny-3class.onnx, a hand-set
// network whose class k is the strongest of input channels R, G, B (after the spec's mean, scale
// and order).
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "test_images.hpp"
#include "tiny_model.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::vision {
namespace {

using test::BgrFrame;

using test::tiny_model;

PipelineConfig dnn_config(WeedSource source = WeedSource::kDnn) {
  PipelineConfig config = default_pipeline_config();
  config.weed_source = source;
  config.rows = 1;
  config.cols = 4;
  config.dnn.input_width = 64;
  config.dnn.input_height = 64;
  config.dnn.mean_rgb = {0, 0, 0};
  config.dnn.scale = 1.0 / 255.0;
  config.dnn.rgb = true;
  return config;
}

constexpr test::Bgr kRed{0, 0, 200};
constexpr test::Bgr kGreen{0, 200, 0};
constexpr test::Bgr kBlue{200, 0, 0};

// 64x64, one colour per 16-px zone column: green, blue, red, green.
BgrFrame stripes() {
  BgrFrame frame(64, 64, kRed);
  const test::Bgr colours[] = {kGreen, kBlue, kRed, kGreen};
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) frame.set(x, y, colours[x / 16]);
  }
  return frame;
}

// The message of the std::invalid_argument that building the pipeline throws ("" if none).
std::string load_error(const PipelineConfig& config, std::span<const std::uint8_t> bytes) {
  try {
    Pipeline pipeline(config, bytes);
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "";
}

TEST(DnnModel, MissingBytesAreAClearError) {
  const std::string message = load_error(dnn_config(), {});
  EXPECT_NE(message.find("weed_source dnn"), std::string::npos) << message;
  EXPECT_NE(message.find("no model bytes"), std::string::npos) << message;
  EXPECT_NE(load_error(dnn_config(WeedSource::kHybrid), {}).find("weed_source hybrid"),
            std::string::npos);
}

TEST(DnnModel, GarbageBytesAreNotALoadableModel) {
  const std::string text = "this is not an ONNX protobuf";
  const std::vector<std::uint8_t> garbage(text.begin(), text.end());
  const std::string message = load_error(dnn_config(), garbage);
  EXPECT_NE(message.find("not a loadable ONNX model"), std::string::npos) << message;
  std::vector<std::uint8_t> truncated = tiny_model();
  truncated.resize(truncated.size() / 2);
  EXPECT_NE(load_error(dnn_config(), truncated), "");
}

TEST(DnnModel, OutputChannelsMustMatchTheClassList) {
  PipelineConfig config = dnn_config();
  config.dnn.classes = {"soil", "crop", "weed", "stone"};
  const std::string message = load_error(config, tiny_model());
  EXPECT_NE(message.find("output shape 1x3x64x64"), std::string::npos) << message;
  EXPECT_NE(message.find("4 classes"), std::string::npos) << message;
}

TEST(DnnModel, ClassIdsMustBeInRangeAndDistinct) {
  PipelineConfig config = dnn_config();
  config.dnn.weed_class = 3;
  std::string message = load_error(config, tiny_model());
  EXPECT_NE(message.find("weed_class = 3"), std::string::npos) << message;
  config = dnn_config();
  config.dnn.crop_class = -1;
  EXPECT_NE(load_error(config, tiny_model()).find("crop_class"), std::string::npos);
  config = dnn_config();
  config.dnn.crop_class = 2;
  message = load_error(config, tiny_model());
  EXPECT_NE(message.find("different"), std::string::npos) << message;
  EXPECT_TRUE(validate_dnn_spec(dnn_config().dnn) == std::nullopt);
  config = dnn_config();
  config.dnn.scale = 0;
  EXPECT_NE(load_error(config, tiny_model()).find("scale"), std::string::npos);
}

TEST(DnnModel, ClassesMapToWeedAndCropDensities) {
  Pipeline pipeline(dnn_config(), tiny_model());
  const BgrFrame frame = stripes();
  const FrameResult& result = pipeline.process(frame.view());
  ASSERT_TRUE(pipeline.last_frame_ok()) << pipeline.last_error();
  // R is soil (class 0), G crop (1), B weed (2). Zone borders blur by a pixel or two.
  EXPECT_GT(result.crop_density[0], 0.9);
  EXPECT_LT(result.zone_density[0], 0.1);
  EXPECT_GT(result.zone_density[1], 0.9);
  EXPECT_LT(result.crop_density[1], 0.1);
  EXPECT_LT(result.zone_density[2] + result.crop_density[2], 0.1);
  EXPECT_GT(result.crop_density[3], 0.9);
  const ImageView classes = pipeline.class_map();
  ASSERT_EQ(classes.width, 64);  // the network's output resolution
  EXPECT_EQ(classes.data[32 * classes.stride + 8], kClassCrop);
  EXPECT_EQ(classes.data[32 * classes.stride + 24], kClassWeed);
  EXPECT_EQ(classes.data[32 * classes.stride + 40], kClassSoil);
}

TEST(DnnModel, ClassIdsChooseWhichClassIsWeed) {
  PipelineConfig config = dnn_config();
  config.dnn.crop_class = 2;  // blue is crop, green weed
  config.dnn.weed_class = 1;
  Pipeline pipeline(config, tiny_model());
  const FrameResult& result = pipeline.process(stripes().view());
  EXPECT_GT(result.zone_density[0], 0.9);
  EXPECT_GT(result.crop_density[1], 0.9);
}

TEST(DnnModel, ChannelOrderFollowsTheSpec) {
  PipelineConfig config = dnn_config();
  config.dnn.rgb = false;  // the network takes B, G, R: a blue pixel reads as its class 0
  Pipeline pipeline(config, tiny_model());
  const FrameResult& result = pipeline.process(stripes().view());
  EXPECT_LT(result.zone_density[1] + result.crop_density[1], 0.1);  // blue -> soil
  EXPECT_GT(result.zone_density[2], 0.9);                           // red -> weed
}

TEST(DnnModel, MeanIsSubtractedPerChannel) {
  PipelineConfig config = dnn_config();
  config.dnn.mean_rgb = {0, 250, 0};  // green falls below red: the green zones become soil
  Pipeline pipeline(config, tiny_model());
  const FrameResult& result = pipeline.process(stripes().view());
  EXPECT_LT(result.crop_density[0], 0.1);
}

TEST(DnnModel, FramesOfOtherSizesAndFormatsAreResizedToTheInput) {
  Pipeline pipeline(dnn_config(), tiny_model());
  BgrFrame frame(256, 128, kRed);
  for (int y = 0; y < 128; ++y) {
    for (int x = 0; x < 64; ++x) frame.set(x, y, kBlue);
  }
  const FrameResult& result = pipeline.process(frame.view());
  ASSERT_TRUE(pipeline.last_frame_ok());
  EXPECT_GT(result.zone_density[0], 0.9);
  EXPECT_LT(result.zone_density[1], 0.1);
  // The same bytes read as RGB: the "blue" column is red to the pipeline.
  ImageView rgb = frame.view();
  rgb.format = PixelFormat::kRgb24;
  EXPECT_LT(pipeline.process(rgb).zone_density[0], 0.1);
}

TEST(GroundScale, TheNetworkInputMatchesTheModelsGroundScale) {
  DnnModelSpec spec;
  spec.ground_mm_per_px = 2.0;
  // 1280 x 800 frame pixels of 1 mm: 640 x 400 model pixels of 2 mm, 400 -> 416 (13 x 32).
  NetworkInputSize input = network_input_size(spec, 1.0, 1280, 800);
  EXPECT_EQ(input.width, 640);
  EXPECT_EQ(input.height, 416);
  EXPECT_DOUBLE_EQ(input.scale, 0.5);
  // A coarser camera is enlarged; the smallest side is one stride.
  input = network_input_size(spec, 3.0, 100, 5);
  EXPECT_EQ(input.width, 160);
  EXPECT_EQ(input.height, 32);
  // Unknown scales or a fixed input: the spec's own size.
  for (const auto& [model_mm, frame_mm, fixed] :
       {std::tuple{0.0, 1.0, false}, std::tuple{2.0, 0.0, false}, std::tuple{2.0, 1.0, true}}) {
    spec.ground_mm_per_px = model_mm;
    spec.fixed_input = fixed;
    input = network_input_size(spec, frame_mm, 1280, 800);
    EXPECT_EQ(input.width, spec.input_width);
    EXPECT_EQ(input.height, spec.input_height);
  }
}

TEST(GroundScale, ThePipelineResamplesEachFrameToTheModelsScale) {
  PipelineConfig config = dnn_config();
  config.dnn.stride = 32;
  config.dnn.ground_mm_per_px = 2.0;
  config.frame_mm_per_px = 0.5;
  Pipeline pipeline(config, tiny_model());
  BgrFrame frame(512, 256, kRed);
  for (int y = 0; y < 256; ++y) {
    for (int x = 0; x < 128; ++x) frame.set(x, y, kBlue);
  }
  const FrameResult& result = pipeline.process(frame.view());
  ASSERT_TRUE(pipeline.last_frame_ok()) << pipeline.last_error();
  EXPECT_EQ(pipeline.network_input().width, 128);
  EXPECT_EQ(pipeline.network_input().height, 64);
  // The classes come back at the frame's resolution whatever the network's.
  const ImageView map = pipeline.class_map();
  EXPECT_EQ(map.width, 512);
  EXPECT_EQ(map.height, 256);
  EXPECT_GT(result.zone_density[0], 0.9);  // blue is class 2, weed
  EXPECT_LT(result.zone_density[1], 0.1);
  // Without the camera's scale the spec's fixed 64 x 64 input is used.
  config.frame_mm_per_px = 0.0;
  Pipeline squeezed(config, tiny_model());
  squeezed.process(frame.view());
  EXPECT_EQ(squeezed.network_input().width, 64);
  EXPECT_EQ(squeezed.network_input().height, 64);
}

TEST(GroundScale, ASpecWhoseSizeIsNotAMultipleOfItsStrideIsRefused) {
  PipelineConfig config = dnn_config();
  config.dnn.stride = 48;
  EXPECT_NE(load_error(config, tiny_model()).find("not a multiple of the network's stride 48"),
            std::string::npos);
  config.dnn.stride = 32;
  config.dnn.input_channels = 1;
  EXPECT_NE(load_error(config, tiny_model()).find("input_channels = 1"), std::string::npos);
}

// Hybrid: a green crop stripe (bright, the network's crop) and two small weeds of a duller
// green (vegetation to the colour index, soil to the network), one 5 px from the crop's edge
// and one 16 px away.
class HybridMargin : public ::testing::Test {
 protected:
  static constexpr test::Bgr kCrop{40, 250, 40};
  BgrFrame frame{64, 64, test::kSoil};
  void SetUp() override {
    for (int y = 0; y < 64; ++y) {
      for (int x = 20; x < 36; ++x) frame.set(x, y, kCrop);
    }
    for (int y = 10; y < 12; ++y) {
      for (int x : {41, 42, 52, 53}) frame.set(x, y, test::kPlant);
    }
  }
  // Weed pixels the hybrid finds with this margin (one zone over the whole frame).
  double weed_pixels(int margin_px) {
    PipelineConfig config = dnn_config(WeedSource::kHybrid);
    config.cols = 1;
    // The network scores G - 100 against R and B: kPlant (G 150, R 60) is soil to it.
    config.dnn.mean_rgb = {0, 100, 0};
    config.threshold = ThresholdMethod::kFixed;  // both greens are vegetation, soil is not
    config.threshold_params.fixed_threshold = 150;
    config.crop_margin_px = margin_px;
    Pipeline pipeline(config, tiny_model());
    const FrameResult& result = pipeline.process(frame.view());
    EXPECT_TRUE(pipeline.last_frame_ok()) << pipeline.last_error();
    EXPECT_NEAR(result.crop_density[0], 16.0 / 64.0, 0.02);
    const ImageView classes = pipeline.class_map();
    near_weed_class = classes.data[10 * classes.stride + 41];
    return result.zone_density[0] * 64 * 64;
  }
  std::uint8_t near_weed_class = 0;
};

TEST_F(HybridMargin, AWeedNextToTheCropIsRemovedWithinTheMarginAndKeptOutsideIt) {
  // Without a margin the crop's edge column, which the network's coarse output misses, is
  // taken for weed: the reason for the margin.
  EXPECT_GT(weed_pixels(0), 8.0);
  EXPECT_NEAR(weed_pixels(1), 8.0, 1e-9);
  EXPECT_EQ(near_weed_class, kClassWeed);
  EXPECT_NEAR(weed_pixels(3), 8.0, 1e-9);  // 5 px from the crop: outside a 3 px margin
  EXPECT_NEAR(weed_pixels(8), 4.0, 1e-9);  // inside an 8 px margin; the far weed stays
  EXPECT_EQ(near_weed_class, kClassCrop);  // protected vegetation is attributed to the crop
  EXPECT_NEAR(weed_pixels(20), 0.0, 1e-9);
}

TEST_F(HybridMargin, PlantsKeepWeedsTooSmallForTheNetworkAndDropSpecks) {
  const auto run = [&](int min_plant_px) {
    PipelineConfig config = dnn_config(WeedSource::kPlants);
    config.cols = 1;
    config.dnn.mean_rgb = {0, 100, 0};
    config.threshold = ThresholdMethod::kFixed;
    config.threshold_params.fixed_threshold = 150;
    config.min_plant_px = min_plant_px;
    Pipeline pipeline(config, tiny_model());
    const FrameResult result = pipeline.process(frame.view());
    EXPECT_TRUE(pipeline.last_frame_ok()) << pipeline.last_error();
    EXPECT_GE(result.crop_density[0], 16.0 / 64.0);  // the stripe, its grown edge included
    const ImageView classes = pipeline.class_map();
    EXPECT_EQ(classes.data[10 * classes.stride + 41], min_plant_px <= 12 ? kClassWeed : kClassSoil);
    return result.zone_density[0] * 64 * 64;
  };
  // Each 2x2 patch, grown by the 1 px join, is a 12 px plant the network calls soil: weed
  // at a least plant of 12 px, a speck at 13.
  EXPECT_NEAR(run(12), 24.0, 1e-9);
  EXPECT_NEAR(run(13), 0.0, 1e-9);
}

TEST_F(HybridMargin, TheDnnAloneMissesWeedsItDoesNotKnow) {
  PipelineConfig config = dnn_config(WeedSource::kDnn);
  config.cols = 1;
  config.dnn.mean_rgb = {0, 100, 0};
  Pipeline pipeline(config, tiny_model());
  EXPECT_DOUBLE_EQ(pipeline.process(frame.view()).zone_density[0], 0.0);
}

// dnn_vegetation: a 32x32 green weed on soil in a 256x256 frame that the network sees at 64x64,
// so it decides on 4x4 blocks and, blurring its edge, marks soil around the weed as weed too.
// Green is the network's class 1, here named the weed. The weed has a soft edge, a 1 px ring
// (corners left out) of a green too dull for the colour threshold, and a 4x4 shaded spot of
// soil colour inside it.
class VegetationEdge : public ::testing::Test {
 protected:
  static constexpr test::Bgr kSoftEdge{60, 120, 110};  // CIVE level ~141: below the threshold
  static constexpr int kBegin = 17, kEnd = 49;         // the weed's square, [kBegin, kEnd)
  BgrFrame frame{256, 256, test::kSoil};
  void SetUp() override {
    for (int i = kBegin; i < kEnd; ++i) {
      for (int j = kBegin; j < kEnd; ++j) frame.set(i, j, test::kPlant);
      frame.set(i, kBegin - 1, kSoftEdge);
      frame.set(i, kEnd, kSoftEdge);
      frame.set(kBegin - 1, i, kSoftEdge);
      frame.set(kEnd, i, kSoftEdge);
    }
    for (int y = 28; y < 32; ++y) {
      for (int x = 28; x < 32; ++x) frame.set(x, y, test::kSoil);
    }
  }
  struct Outcome {
    double weed_px = 0.0;
    std::uint8_t beside = 0;  // class of the soil 3 px right of the weed
    std::uint8_t ring = 0;    // class of the soft edge left of the weed
    std::uint8_t shaded = 0;  // class of the shaded spot
  };
  Outcome run(WeedSource source) {
    PipelineConfig config = dnn_config(source);
    config.cols = 1;
    config.dnn.weed_class = 1;
    config.dnn.crop_class = 2;
    config.threshold = ThresholdMethod::kFixed;  // the plant is vegetation, the rest is not
    config.threshold_params.fixed_threshold = 150;
    Pipeline pipeline(config, tiny_model());
    const FrameResult result = pipeline.process(frame.view());
    EXPECT_TRUE(pipeline.last_frame_ok()) << pipeline.last_error();
    const ImageView classes = pipeline.class_map();
    const auto at = [&](int x, int y) {
      return classes.data[(y * classes.height / 256) * classes.stride + x * classes.width / 256];
    };
    return {result.zone_density[0] * 256 * 256, at(kEnd + 3, 32), at(kBegin - 1, 32), at(29, 29)};
  }
};

TEST_F(VegetationEdge, ColourTrimsTheNetworksEdgeAndLeavesItsInterior) {
  const Outcome dnn = run(WeedSource::kDnn);
  const Outcome kept = run(WeedSource::kDnnVegetation);
  // The network's blocks reach past the weed (soil beside it is weed) and over the shaded spot.
  EXPECT_EQ(dnn.beside, kClassWeed);
  EXPECT_EQ(dnn.shaded, kClassWeed);
  // In the network's outer block colour decides: the soil beside the weed is soil, the soft
  // edge (in that block, grown into by the 1 px join) stays weed. Further in, the network's
  // class stands: the shaded spot stays weed although colour finds no plant there.
  EXPECT_EQ(kept.beside, kClassSoil);
  EXPECT_EQ(kept.ring, kClassWeed);
  EXPECT_EQ(kept.shaded, kClassWeed);
  EXPECT_GE(kept.weed_px, 32.0 * 32.0);
  EXPECT_LT(kept.weed_px, dnn.weed_px - 100.0) << kept.weed_px << " of " << dnn.weed_px;
}

TEST_F(VegetationEdge, VegetationTheNetworkCallsSoilStaysSoil) {
  // A dull green speck the network calls soil (G - 100 loses to R and B) is not made weed:
  // colour only trims the network's classes, it adds none (unlike hybrid and plants).
  PipelineConfig config = dnn_config(WeedSource::kDnnVegetation);
  config.cols = 1;
  config.dnn.mean_rgb = {0, 100, 0};
  config.threshold = ThresholdMethod::kFixed;
  config.threshold_params.fixed_threshold = 150;
  Pipeline pipeline(config, tiny_model());
  const FrameResult result = pipeline.process(frame.view());
  EXPECT_TRUE(pipeline.last_frame_ok()) << pipeline.last_error();
  EXPECT_DOUBLE_EQ(result.zone_density[0], 0.0);
  EXPECT_DOUBLE_EQ(result.crop_density[0], 0.0);
}

}  // namespace
}  // namespace weedspray::vision
