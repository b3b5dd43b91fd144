// SPDX-License-Identifier: Apache-2.0
// The savings experiment's field from labelled crop/weed photos (lab/experiment_field): zone
// truth from class-id masks, and the weed density the sprayer acts on.
#include "lab/experiment_field.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "lab/weed_model.hpp"

namespace weedspray::lab {
namespace {

// 40 x 20 mask: weed fills the top-left zone (far row, nozzle 0), crop a quarter of the
// bottom-right zone (near row, nozzle 3).
cv::Mat example_mask() {
  cv::Mat mask(20, 40, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(0, 0, 10, 10)).setTo(2);
  mask(cv::Rect(30, 10, 5, 5)).setTo(1);
  return mask;
}

TEST(SavingsField, MaskZoneTruthInTrackOrder) {
  const auto rows = mask_zone_truth(example_mask());
  ASSERT_EQ(rows.size(), 2u);
  // Near (bottom) row first.
  EXPECT_DOUBLE_EQ(rows[0][3].crop, 0.25);
  EXPECT_DOUBLE_EQ(rows[0][3].weed, 0.0);
  EXPECT_DOUBLE_EQ(rows[1][0].weed, 1.0);
  EXPECT_DOUBLE_EQ(rows[1][1].weed, 0.0);
  EXPECT_THROW(mask_zone_truth(cv::Mat()), std::invalid_argument);
}

// Two labelled photos: brown soil, green where the mask says crop or weed.
std::vector<LabelledImage> example_photos() {
  const cv::Mat mask = example_mask();
  cv::Mat image(mask.size(), CV_8UC3, cv::Scalar(70, 100, 130));
  image.setTo(cv::Scalar(40, 150, 60), mask != 0);
  return {{"a", image, mask != 0, mask}, {"b", image, mask != 0, mask}};
}

TEST(SavingsField, TruthAndVegetationDensities) {
  const std::vector<LabelledImage> photos = example_photos();
  const LabelledField truth = labelled_field(photos, std::nullopt);
  ASSERT_EQ(truth.weed_density.size(), 4u);  // 2 photos x 2 zone rows
  ASSERT_EQ(truth.truth.size(), 4u);
  EXPECT_DOUBLE_EQ(truth.weed_density[1][0], 1.0);
  EXPECT_DOUBLE_EQ(truth.weed_density[0][3], 0.0);  // crop is not weed

  // Today's behaviour: every green pixel counts, the crop too.
  const LabelledField green = labelled_field(photos, vision::default_pipeline_config());
  ASSERT_EQ(green.weed_density.size(), 4u);
  EXPECT_DOUBLE_EQ(green.weed_density[1][0], 1.0);
  EXPECT_DOUBLE_EQ(green.weed_density[0][3], 0.25);
  EXPECT_DOUBLE_EQ(green.weed_density[0][0], 0.0);
  EXPECT_DOUBLE_EQ(green.truth[0][3].crop, 0.25);
}

// The savings experiment's field on the peanut validation photos: acting on true weeds sprays
// no crop-only zone; acting on all vegetation (today's default) sprays nearly all of them and
// uses more liquid. Missing data is a failure, not a skip.
TEST(SavingsField, PeanutValidationPhotos) {
  const char* data_dir = std::getenv("WEEDSPRAY_DATA_DIR");
  const std::filesystem::path peanut = std::filesystem::path(data_dir ? data_dir : "") / "peanut";
  ASSERT_TRUE(std::filesystem::is_directory(peanut / "images"))
      << peanut << " not found (WEEDSPRAY_DATA_DIR)";
  const std::vector<LabelledImage> photos =
      load_labelled_images(peanut / "images", peanut / "masks",
                           read_stem_list(std::filesystem::path(WEEDSPRAY_SOURCE_DIR) /
                                          "tools/train/splits/peanut-val.txt"));
  ASSERT_EQ(photos.size(), 60u);
  lab::experiments::SavingsOptions options;
  options.max_density = 1.0;
  options.decision_threshold = 0.005;  // = the weedy share: truth leaves no weedy zone dry
  const LabelledField truth = labelled_field(photos, std::nullopt);
  const LabelledField green = labelled_field(photos, vision::default_pipeline_config());
  const auto on_truth = lab::experiments::run_savings(truth.weed_density, options);
  const auto on_green = lab::experiments::run_savings(green.weed_density, options);
  const auto truth_tally = tally_against_truth(on_truth.equal_coverage, truth.truth);
  const auto green_tally = tally_against_truth(on_green.equal_coverage, green.truth);
  EXPECT_GT(truth_tally.weedy_zones, 200);
  EXPECT_GT(truth_tally.crop_only_zones, 50);
  EXPECT_EQ(truth_tally.weedy_left_dry, 0);
  EXPECT_EQ(truth_tally.crop_only_sprayed, 0);
  EXPECT_GT(green_tally.crop_only_sprayed, 0.9 * green_tally.crop_only_zones);
  EXPECT_GT(on_truth.savings_pct, on_green.savings_pct + 5.0);

  // The shipped crop/weed network, which never saw these photos: it spares most of the
  // crop-only zones that vegetation sprays, and leaves few weedy zones dry.
  const WeedModel model =
      read_weed_model(std::filesystem::path(WEEDSPRAY_SOURCE_DIR) / "models/weed-peanut.onnx");
  ASSERT_TRUE(model.spec_from_json);
  vision::PipelineConfig dnn = vision::default_pipeline_config();
  dnn.weed_source = vision::WeedSource::kDnn;
  dnn.dnn = model.spec;
  const LabelledField predicted = labelled_field(photos, dnn, model.onnx);
  const auto on_dnn = lab::experiments::run_savings(predicted.weed_density, options);
  const auto dnn_tally = tally_against_truth(on_dnn.equal_coverage, predicted.truth);
  EXPECT_LT(dnn_tally.crop_only_sprayed, 0.6 * green_tally.crop_only_sprayed);
  EXPECT_LT(dnn_tally.weedy_left_dry, 0.15 * dnn_tally.weedy_zones);
  EXPECT_GT(on_dnn.savings_pct, on_green.savings_pct);
}

}  // namespace
}  // namespace weedspray::lab
