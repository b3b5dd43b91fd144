// SPDX-License-Identifier: Apache-2.0
// Agreement with the 142 hand-labelled EWS field images (data/ews-train), through the same
// evaluation code as `weedspray-lab vision-eval`. The expected figures are that command's
// measured output; the margins are small so a regression in any stage shows.
#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <filesystem>

#include "lab/vision_eval.hpp"

namespace weedspray::lab {
namespace {

// Measured by: weedspray-lab vision-eval --images DATA/ews-train/images --masks
// DATA/ews-train/masks
constexpr double kDefaultIou = 0.6040;
// weedspray-lab vision-eval --images DATA/peanut/images --masks DATA/peanut/masks (plant =
// crop or weed), CIVE + Otsu.
constexpr double kPeanutDefaultIou = 0.7318;
constexpr double kExgFitIou = 0.5249;
constexpr double kExgFitThresholdError = 0.070;

std::filesystem::path data_folder(const char* name) {
  const char* data_dir = std::getenv("WEEDSPRAY_DATA_DIR");
  return std::filesystem::path(data_dir ? data_dir : "") / name;
}
std::filesystem::path ews_folder() {
  return data_folder("ews-train");
}

// Mean plant IoU of the default pipeline with the given unimodal policy.
double default_iou(const std::vector<LabelledImage>& images, vision::UnimodalPolicy policy) {
  vision::PipelineConfig config = vision::default_pipeline_config();
  config.threshold_params.unimodal = policy;
  const std::array indices{config.index};
  const std::array methods{config.threshold};
  return evaluate_combinations(images, indices, methods, config).front().mean_iou;
}

class EwsTrain : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::filesystem::path folder = ews_folder();
    if (std::filesystem::is_directory(folder / "images")) {
      images_ =
          new std::vector<LabelledImage>(load_labelled_images(folder / "images", folder / "masks"));
    }
  }
  static void TearDownTestSuite() {
    delete images_;
    images_ = nullptr;
  }
  void SetUp() override {
    // The figures are the point of these tests: missing data is a failure, not a skip.
    ASSERT_NE(images_, nullptr) << ews_folder() << " not found (WEEDSPRAY_DATA_DIR)";
    ASSERT_EQ(images_->size(), 142U) << "the EWS training split has 142 images";
  }
  static EvalRow evaluate(vision::VegetationIndex index, vision::ThresholdMethod method) {
    const std::array indices{index};
    const std::array methods{method};
    return evaluate_combinations(*images_, indices, methods, vision::default_pipeline_config())
        .front();
  }
  static std::vector<LabelledImage>* images_;
};
std::vector<LabelledImage>* EwsTrain::images_ = nullptr;

TEST_F(EwsTrain, AllImagesLoad) {
  EXPECT_EQ(images_->size(), 142u);
}

TEST_F(EwsTrain, DefaultPipelineReachesItsMeasuredIou) {
  const vision::PipelineConfig config = vision::default_pipeline_config();
  const EvalRow row = evaluate(config.index, config.threshold);
  EXPECT_GE(row.mean_iou, 0.58);
  EXPECT_NEAR(row.mean_iou, kDefaultIou, 0.005);
}

// The default's answer on frames that do not look bimodal beats both the fixed CIVE level and
// the papers' keep-the-split, and holds the floor of 0.60.
TEST_F(EwsTrain, DefaultUnimodalPolicyBeatsFixedScaleAndKeepSplit) {
  const double iou = default_iou(*images_, vision::UnimodalPolicy::kIndexDefault);
  EXPECT_GE(iou, 0.60);
  EXPECT_GT(iou, default_iou(*images_, vision::UnimodalPolicy::kFixedScale));
  EXPECT_GT(iou, default_iou(*images_, vision::UnimodalPolicy::kKeepSplit));
}

// The same rule on another crop and camera (data/peanut, plant = crop or weed): it must
// transfer, not only fit the wheat images it was chosen on.
TEST(PeanutPlants, DefaultUnimodalPolicyTransfers) {
  const std::filesystem::path folder = data_folder("peanut");
  ASSERT_TRUE(std::filesystem::is_directory(folder / "images"))
      << folder << " not found (WEEDSPRAY_DATA_DIR)";
  const std::vector<LabelledImage> images =
      load_labelled_images(folder / "images", folder / "masks");
  const double iou = default_iou(images, vision::UnimodalPolicy::kIndexDefault);
  EXPECT_NEAR(iou, kPeanutDefaultIou, 0.005);
  EXPECT_GT(iou, default_iou(images, vision::UnimodalPolicy::kFixedScale));
  EXPECT_GT(iou, default_iou(images, vision::UnimodalPolicy::kKeepSplit));
}

// The UGV paper's choice, normalised ExG + FIT, as measured here.
TEST_F(EwsTrain, NormalisedExgWithFitAsMeasured) {
  const EvalRow row =
      evaluate(vision::VegetationIndex::kExgNormalized, vision::ThresholdMethod::kFit);
  EXPECT_NEAR(row.mean_iou, kExgFitIou, 0.01);
  EXPECT_NEAR(row.threshold_error, kExgFitThresholdError, 0.05);
}

}  // namespace
}  // namespace weedspray::lab
