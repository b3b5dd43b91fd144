// SPDX-License-Identifier: Apache-2.0
// [vision] weed source keys: the model is found, read and run once at load, and every
// problem with it is a ConfigError naming the file, line and key.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "daemon/config/config.hpp"
#include "daemon/config/config_schema.hpp"
#include "daemon/config/model_timing.hpp"
#include "daemon/config/vision_config.hpp"
#include "vision/weed_source.hpp"

namespace weedspray::daemon {
namespace {

namespace fs = std::filesystem;

// Hand-set 3-class net (tools/train/make_tiny_onnx.py): with mean 0 and scale 1/255 in R, G, B
// order a red pixel is class 0, green class 1, blue class 2.
const fs::path kTinyModel = fs::path(WEEDSPRAY_SOURCE_DIR) / "tests/data/tiny-3class.onnx";

std::string tiny_dnn(const std::string& extra = "") {
  return "[vision]\nweed_source = \"dnn\"\nmodel = \"" + kTinyModel.string() +
         "\"\nmodel_mean = [0, 0, 0]\nmodel_scale = 0.00392156862745098\n" + extra;
}

Config parse_weed_config(const std::string& text) {
  return load_config_from_strings({{"main.toml", text}});
}

ConfigError parse_error(const std::string& text) {
  try {
    (void)parse_weed_config(text);
  } catch (const ConfigError& error) {
    return error;
  }
  ADD_FAILURE() << "no ConfigError for:\n" << text;
  return ConfigError("", 0, "", "");
}

TEST(WeedSourceConfig, DefaultIsVegetationAndLoadsNoModel) {
  const Config config = parse_weed_config("");
  EXPECT_EQ(config.vision.weed_source, "vegetation");
  EXPECT_EQ(config.model, nullptr);
  // Model keys are not checked while no source uses them.
  EXPECT_NO_THROW(
      (void)parse_weed_config("[vision]\nmodel = \"/nonexistent.onnx\"\nmodel_input_width = 100\n"
                              "weed_class = 7\n"));
  EXPECT_EQ(parse_weed_config("[vision]\nweed_source = \"inter_row\"\n").model, nullptr);
}

TEST(WeedSourceConfig, ChoicesAreTheVisionLibrarysNames) {
  for (const auto& spec : config_keys()) {
    if (spec.full_name() != "vision.weed_source") continue;
    ASSERT_EQ(spec.choices.size(), vision::weed_source_names().size());
    for (auto choice : spec.choices) EXPECT_TRUE(vision::parse_weed_source(choice)) << choice;
    return;
  }
  FAIL() << "no vision.weed_source key";
}

TEST(WeedSourceConfig, DnnReadsTheModelOnce) {
  const Config config = parse_weed_config(tiny_dnn());
  ASSERT_NE(config.model, nullptr);
  EXPECT_EQ(config.model->path, kTinyModel);
  EXPECT_EQ(config.model->onnx.size(), fs::file_size(kTinyModel));
  EXPECT_NE(parse_weed_config(tiny_dnn()).model, nullptr);
}

// The model keys' defaults are the shipped model and its spec: one line switches to it (a
// build tree finds it in the checkout's models/, an installed daemon in its data folder).
TEST(WeedSourceConfig, DefaultModelIsTheShippedOne) {
  const Config config = parse_weed_config("[vision]\nweed_source = \"hybrid\"\n");
  ASSERT_NE(config.model, nullptr);
  EXPECT_EQ(config.model->path, fs::path(WEEDSPRAY_SOURCE_DIR) / "models" / "weed-peanut-2mm.onnx");
}

// A model folder of its own: the tiny network with a description written by the test.
class OwnModel : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("weedspray-own-model-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    fs::copy_file(kTinyModel, model());
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path model() const { return dir_ / "own.onnx"; }
  // The description with `spec` inside "spec": {...}.
  void describe(const std::string& spec) {
    std::ofstream(dir_ / "own.json") << "{\"spec\": {" << spec << "}, \"licence\": \"MIT\"}\n";
  }
  std::string dnn(const std::string& extra = "") const {
    return "[vision]\nweed_source = \"dnn\"\nmodel = \"" + model().string() + "\"\n" + extra;
  }
  static constexpr const char* kBgrSpec =
      "\"input_width\": 64, \"input_height\": 64, \"mean_rgb\": [0, 0, 0], "
      "\"scale\": 0.00392156862745098, \"rgb\": false, \"classes\": [\"bg\", \"weed\", \"crop\"], "
      "\"soil_class\": 0, \"weed_class\": 1, \"crop_class\": 2, \"ground_mm_per_px\": 2.0";
  fs::path dir_;
};

TEST_F(OwnModel, PipelineGetsTheModelsSpecAndGroundDistancesInPixels) {
  describe(kBgrSpec);
  // The camera's own ground scale converts ground distances, not the nozzles' span (4 x 0.5 m).
  const Config config =
      parse_weed_config(dnn("crop_margin_cm = 2.0\nrow_band_cm = 30.0\nmin_plant_cm2 = 0.5\n") +
                        "[[camera]]\nground_mm_per_px = 1.25\n");
  ASSERT_EQ(config.cameras.size(), 1U);
  ASSERT_NE(config.model, nullptr);
  EXPECT_EQ(config.model->licence, "MIT");
  const vision::PipelineConfig c = pipeline_config(config, config.cameras[0]);
  EXPECT_EQ(c.weed_source, vision::WeedSource::kDnn);
  EXPECT_EQ(c.cols, 4);
  EXPECT_EQ(c.crop_margin_px, 16);                               // 20 mm / 1.25 mm
  EXPECT_EQ(c.min_plant_px, 32);                                 // 50 mm2 / 1.5625 mm2
  EXPECT_DOUBLE_EQ(c.inter_row_rule.row_band_fraction, 0.1875);  // 30 cm of 1280 x 1.25 mm
  EXPECT_FALSE(c.dnn.rgb);
  EXPECT_EQ(c.dnn.weed_class, 1);
  EXPECT_EQ(c.dnn.crop_class, 2);
  EXPECT_DOUBLE_EQ(c.dnn.mean_rgb[1], 0.0);
  EXPECT_EQ(c.dnn.classes[2], "crop");
  EXPECT_DOUBLE_EQ(c.dnn.ground_mm_per_px, 2.0);
  EXPECT_FALSE(c.dnn.fixed_input);
  EXPECT_DOUBLE_EQ(c.frame_mm_per_px, camera_ground_mm_per_px(config.cameras[0]));
}

TEST_F(OwnModel, CheckConfigSaysHowEachCameraMeetsTheModel) {
  describe(kBgrSpec);
  // 1.008 mm/px to the model's 2 mm/px: 1280 x 800 -> 645 x 403 -> 640 x 416 (strides of 32).
  const auto lines = describe_model_use(parse_weed_config(dnn()));
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_NE(lines[0].find("camera[0]: 1.01 mm/px -> own.onnx (learnt at 2 mm/px; MIT): network "
                          "input 640x416"),
            std::string::npos)
      << lines[0];
  EXPECT_TRUE(describe_model_use(parse_weed_config("")).empty());
}

TEST_F(OwnModel, CheckConfigTimesEachCamerasFramesThroughTheModel) {
  describe(kBgrSpec);
  const auto lines =
      time_model_use(parse_weed_config(dnn() + "[boom]\nnozzles = 8\n[[camera]]\n[[camera]]\n"
                                               "width = 640\nheight = 400\nfirst_nozzle = 4\n"));
  ASSERT_EQ(lines.size(), 2U);
  EXPECT_NE(lines[0].find("camera[0]: dnn on 1280x800 frames: "), std::string::npos) << lines[0];
  EXPECT_NE(lines[1].find("camera[1]: dnn on 640x400 frames: "), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find(" ms per frame on this machine (one thread)"), std::string::npos);
  EXPECT_TRUE(time_model_use(parse_weed_config("")).empty());
}

TEST_F(OwnModel, KeysThatDisagreeWithTheModelAreRefusedByName) {
  describe(kBgrSpec);
  const std::vector<std::tuple<std::string, std::string, int>> cases = {
      {"model_rgb = true\n", "vision.model_rgb", 4},
      {"model_scale = 0.5\n", "vision.model_scale", 4},
      {"model_mean = [1.0, 2.0, 3.0]\n", "vision.model_mean", 4},
      {"model_classes = [\"soil\", \"crop\", \"weed\"]\n", "vision.model_classes", 4},
      {"weed_class = 2\ncrop_class = 1\n", "vision.crop_class", 5},
  };
  for (const auto& [line, key, number] : cases) {
    const auto e = parse_error(dnn(line));
    EXPECT_EQ(e.key(), key) << line;
    EXPECT_EQ(e.line(), number) << line;
    EXPECT_NE(std::string(e.what()).find("own.json says"), std::string::npos) << e.what();
  }
  // Keys that agree with it are fine.
  EXPECT_NO_THROW(
      (void)parse_weed_config(dnn("model_rgb = false\nweed_class = 1\ncrop_class = 2\n")));
}

TEST_F(OwnModel, AModelWithoutItsDescriptionIsRefused) {
  const auto e = parse_error(dnn());
  EXPECT_EQ(e.key(), "vision.model");
  EXPECT_NE(std::string(e.what()).find("own.json"), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find("no description"), std::string::npos) << e.what();
  describe("\"input_width\": 64");
  const auto partial = parse_error(dnn());
  EXPECT_NE(std::string(partial.what()).find("spec.input_height: missing"), std::string::npos)
      << partial.what();
  describe(std::string(kBgrSpec) + ", \"stride\": 48");
  const auto stride = parse_error(dnn());
  EXPECT_NE(std::string(stride.what()).find("not a multiple of the network's stride 48"),
            std::string::npos)
      << stride.what();
}

TEST_F(OwnModel, ADescriptionWithMoreClassesThanTheOutputIsRefused) {
  describe(
      "\"input_width\": 64, \"input_height\": 64, \"mean_rgb\": [0, 0, 0], \"scale\": 1, "
      "\"rgb\": true, \"classes\": [\"soil\", \"crop\", \"weed\", \"rock\"], "
      "\"soil_class\": 0, \"crop_class\": 1, \"weed_class\": 2");
  const auto e = parse_error(dnn());
  EXPECT_EQ(e.key(), "vision.model");
  EXPECT_NE(std::string(e.what()).find("output shape 1x3x64x64 is not 1 x 4 classes"),
            std::string::npos)
      << e.what();
}

TEST_F(OwnModel, AGreyCameraCannotFeedAColourModel) {
  describe(kBgrSpec);
  const auto e = parse_error(dnn("[[camera]]\nformat = \"GREY\"\n"));
  EXPECT_EQ(e.key(), "camera[0].format");
  EXPECT_EQ(e.line(), 5);
  EXPECT_NE(std::string(e.what()).find("takes 3 colour channels"), std::string::npos) << e.what();
  // Without a model a GREY camera is fine.
  EXPECT_NO_THROW((void)parse_weed_config("[[camera]]\nformat = \"GREY\"\n"));
}

TEST_F(OwnModel, TheCamerasGroundScaleMustSuitTheModel) {
  describe(kBgrSpec);  // learnt at 2 mm per network pixel
  // 1 m up, looking 30 deg forward, 40 deg over 800 rows: 1.155 m x 0.873 mrad = 1.008 mm/px.
  const Config config = parse_weed_config(dnn());
  EXPECT_NEAR(camera_ground_mm_per_px(config.cameras[0]), 1.0077, 1e-3);
  const auto coarse = parse_error(dnn("[[camera]]\nground_mm_per_px = 4.5\n"));
  EXPECT_EQ(coarse.key(), "camera[0].ground_mm_per_px");
  EXPECT_NE(std::string(coarse.what()).find("more than 2x"), std::string::npos) << coarse.what();
  const auto high = parse_error(dnn("[[camera]]\nmount_height_m = 5.0\n"));
  EXPECT_EQ(high.key(), "camera[0].mount_height_m");
  // 5 m up: 5.04 mm/px, 2.5x coarser. 0.5 mm/px over 1280x800 needs 320x192 at 2 mm/px.
  EXPECT_NO_THROW((void)parse_weed_config(dnn("[[camera]]\nground_mm_per_px = 0.5\n")));
  // 0.15 mm/px against a 0.1 mm/px model: 1920 x 1200 network pixels, over 1.5 M.
  describe(std::string(kBgrSpec).replace(std::string(kBgrSpec).find("2.0"), 3, "0.1"));
  const auto big = parse_error(dnn("[[camera]]\nground_mm_per_px = 0.15\n"));
  EXPECT_EQ(big.key(), "camera[0].ground_mm_per_px");
  EXPECT_NE(std::string(big.what()).find("vision.max_network_pixels"), std::string::npos)
      << big.what();
  EXPECT_NO_THROW((void)parse_weed_config(
      dnn("max_network_pixels = 4000000\n[[camera]]\nground_mm_per_px = 0.15\n")));
  // An input size set in the file squeezes the region to it, whatever the scales.
  const Config fixed = parse_weed_config(
      dnn("model_input_width = 96\nmodel_input_height = 64\n[[camera]]\nground_mm_per_px = 9\n"));
  const vision::PipelineConfig c = pipeline_config(fixed, fixed.cameras[0]);
  EXPECT_TRUE(c.dnn.fixed_input);
  EXPECT_EQ(c.dnn.input_width, 96);
}

TEST(WeedSourceConfig, MissingModelNamesKeyFileAndLine) {
  const auto e = parse_error("[vision]\nweed_source = \"dnn\"\nmodel = \"/nonexistent/m.onnx\"\n");
  EXPECT_EQ(e.file(), "main.toml");
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.key(), "vision.model");
  EXPECT_NE(std::string(e.what()).find("/nonexistent/m.onnx does not exist"), std::string::npos)
      << e.what();
  // A relative path names every place it was looked for.
  const auto relative = parse_error("[vision]\nweed_source = \"hybrid\"\nmodel = \"nope.onnx\"\n");
  EXPECT_EQ(relative.key(), "vision.model");
  EXPECT_NE(std::string(relative.what()).find("nope.onnx not found (looked for ./nope.onnx"),
            std::string::npos)
      << relative.what();
}

TEST(WeedSourceConfig, UnloadableModelIsNamed) {
  const fs::path junk =
      fs::temp_directory_path() / ("weedspray-junk-" + std::to_string(getpid()) + ".onnx");
  std::ofstream(junk) << "not an ONNX model";
  fs::copy_file(fs::path(kTinyModel).replace_extension(".json"),
                fs::path(junk).replace_extension(".json"), fs::copy_options::overwrite_existing);
  const auto e =
      parse_error("[vision]\nweed_source = \"dnn\"\n\nmodel = \"" + junk.string() + "\"\n");
  fs::remove(junk);
  fs::remove(fs::path(junk).replace_extension(".json"));
  EXPECT_EQ(e.key(), "vision.model");
  EXPECT_EQ(e.line(), 4);
  EXPECT_NE(std::string(e.what()).find("not a loadable ONNX model"), std::string::npos) << e.what();
  const auto folder = parse_error("[vision]\nweed_source = \"dnn\"\nmodel = \"/tmp\"\n");
  EXPECT_EQ(folder.key(), "vision.model");
  EXPECT_NE(std::string(folder.what()).find("not a regular file"), std::string::npos);
  // A device would be read forever.
  const auto device = parse_error("[vision]\nweed_source = \"dnn\"\nmodel = \"/dev/zero\"\n");
  EXPECT_NE(std::string(device.what()).find("/dev/zero is not a regular file"), std::string::npos)
      << device.what();
}

TEST(WeedSourceConfig, OutputChannelsMustMatchTheClassList) {
  const auto e =
      parse_error(tiny_dnn("model_classes = [\"soil\", \"crop\", \"weed\", \"rock\"]\n"));
  EXPECT_EQ(e.key(), "vision.model_classes");
  EXPECT_EQ(e.line(), 6);
  EXPECT_NE(std::string(e.what()).find("4 classes"), std::string::npos) << e.what();
}

TEST(WeedSourceConfig, ClassIdsMustBeClassesAndDistinct) {
  const auto out = parse_error(tiny_dnn("weed_class = 3\n"));
  EXPECT_EQ(out.key(), "vision.weed_class");
  EXPECT_EQ(out.line(), 6);
  EXPECT_NE(std::string(out.what()).find("not a class of model_classes (0..2)"), std::string::npos)
      << out.what();
  // The key the file set is named, not the one left at its default.
  const auto same = parse_error(tiny_dnn("crop_class = 2\n"));
  EXPECT_EQ(same.key(), "vision.crop_class");
  EXPECT_EQ(same.line(), 6);
  EXPECT_NE(std::string(same.what()).find("already vision.weed_class"), std::string::npos)
      << same.what();
  const auto too_few = parse_error(tiny_dnn("model_classes = [\"weed\"]\n"));
  EXPECT_EQ(too_few.key(), "vision.model_classes");
}

TEST(WeedSourceConfig, InputSizeIsAMultipleOf32) {
  const auto e = parse_error(tiny_dnn("model_input_height = 250\n"));
  EXPECT_EQ(e.key(), "vision.model_input_height");
  EXPECT_EQ(e.line(), 6);
  EXPECT_NE(std::string(e.what()).find("not a multiple of 32"), std::string::npos) << e.what();
  EXPECT_NO_THROW(
      (void)parse_weed_config(tiny_dnn("model_input_width = 384\nmodel_input_height = 288\n")));
}

TEST(WeedSourceConfig, MeanIsThreeNumbers) {
  const auto e = parse_error("[vision]\nweed_source = \"dnn\"\nmodel = \"" + kTinyModel.string() +
                             "\"\nmodel_mean = [1.0, 2.0]\n");
  EXPECT_EQ(e.key(), "vision.model_mean");
  EXPECT_EQ(e.line(), 4);
  EXPECT_EQ(parse_error("[vision]\nmodel_mean = [1, \"x\", 3]\n").key(), "vision.model_mean");
  EXPECT_EQ(parse_error("[vision]\nmodel_mean = [1, 300, 3]\n").key(), "vision.model_mean");
}

TEST(WeedSourceConfig, RowBandMustBeNarrowerThanTheView) {
  const auto e = parse_error("[vision]\nweed_source = \"inter_row\"\nrow_band_cm = 250\n");
  EXPECT_EQ(e.key(), "vision.row_band_cm");
  EXPECT_EQ(e.line(), 3);
  EXPECT_NE(std::string(e.what()).find("camera[0]"), std::string::npos) << e.what();
}

class WeedModelFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("weedspray-model-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "conf.d");
    fs::create_directories(dir_ / "models");
    fs::copy_file(kTinyModel, dir_ / "models" / "tiny.onnx");
    fs::copy_file(fs::path(kTinyModel).replace_extension(".json"), dir_ / "models" / "tiny.json");
  }
  void TearDown() override { fs::remove_all(dir_); }
  void write(const fs::path& relative, const std::string& text) {
    std::ofstream(dir_ / relative) << text;
  }
  fs::path dir_;
};

TEST_F(WeedModelFiles, RelativeModelIsFoundBesideTheFileThatSetsIt) {
  const std::string spec = "model_mean = [0, 0, 0]\nmodel_scale = 0.00392156862745098\n";
  write("weedspray.toml", "[vision]\nweed_source = \"dnn\"\nmodel = \"models/tiny.onnx\"\n" + spec);
  EXPECT_EQ(load_config(dir_ / "weedspray.toml").model->path, dir_ / "models" / "tiny.onnx");
  // A drop-in's path is relative to conf.d/.
  write("conf.d/50-model.toml", "[vision]\nmodel = \"../models/tiny.onnx\"\n");
  EXPECT_EQ(load_config(dir_ / "weedspray.toml").model->path,
            dir_ / "conf.d" / ".." / "models" / "tiny.onnx");
  write("conf.d/50-model.toml", "[vision]\nmodel = \"models/tiny.onnx\"\n");
  try {
    (void)load_config(dir_ / "weedspray.toml");
    FAIL() << "conf.d/models/tiny.onnx does not exist";
  } catch (const ConfigError& e) {
    EXPECT_NE(e.file().find("50-model.toml"), std::string::npos);
    EXPECT_EQ(e.key(), "vision.model");
  }
}

}  // namespace
}  // namespace weedspray::daemon
