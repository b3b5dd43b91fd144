// SPDX-License-Identifier: Apache-2.0
// vision-eval --classes end to end on a synthetic labelled field whose answer is known.
#include "lab/weed_eval.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

namespace weedspray::lab {
namespace {

// 200x100: soil, two 16-px crop rows (x 32..47, 132..147), a 10x10 weed at x 85..94 (zone 1
// of a 1x4 grid) and a 4x4 weed at x 180..183 (zone 3); masks hold the class ids.
LabelledImage synthetic_field() {
  LabelledImage image;
  image.name = "synthetic";
  image.bgr = cv::Mat(100, 200, CV_8UC3, cv::Scalar(70, 100, 130));
  image.mask = cv::Mat(100, 200, CV_8UC1, cv::Scalar(0));
  const cv::Scalar plant(40, 150, 60);
  for (const int x : {32, 132}) {
    image.bgr(cv::Rect(x, 0, 16, 100)).setTo(plant);
    image.mask(cv::Rect(x, 0, 16, 100)).setTo(1);
  }
  image.bgr(cv::Rect(85, 40, 10, 10)).setTo(plant);
  image.mask(cv::Rect(85, 40, 10, 10)).setTo(2);
  image.bgr(cv::Rect(180, 40, 4, 4)).setTo(plant);
  image.mask(cv::Rect(180, 40, 4, 4)).setTo(2);
  image.plant = image.mask != 0;
  return image;
}

ZoneRule one_row_of_four() {
  ZoneRule rule;
  rule.rows = 1;
  rule.cols = 4;
  rule.weedy_share = 0.005;        // 25 of 5000 px
  rule.decision_threshold = 0.01;  // the 10x10 weed (2 %) sprays, the 4x4 (0.32 %) does not
  return rule;
}

TEST(WeedEval, InterRowSeparatesRowsFromWeedsExactly) {
  vision::PipelineConfig config = vision::default_pipeline_config();
  config.weed_source = vision::WeedSource::kInterRow;
  const WeedEvalRow row =
      evaluate_weed_source({synthetic_field()}, config, {}, one_row_of_four(), true);
  EXPECT_DOUBLE_EQ(row.scores.iou[0], 1.0);
  EXPECT_DOUBLE_EQ(row.scores.iou[1], 1.0);
  EXPECT_DOUBLE_EQ(row.scores.iou[2], 1.0);
  EXPECT_DOUBLE_EQ(row.scores.miou, 1.0);
  EXPECT_DOUBLE_EQ(row.scores.mpa, 1.0);
  EXPECT_DOUBLE_EQ(row.vegetation_iou, 1.0);
  // Zone 1 (2 % weed) is weedy and sprayed; zone 3 (0.32 %) is under the weedy share.
  EXPECT_EQ(row.zones.weedy, 1);
  EXPECT_DOUBLE_EQ(row.zones.recall(), 1.0);
  EXPECT_EQ(row.zones.clean, 3);
  EXPECT_DOUBLE_EQ(row.zones.clean_left_dry(), 1.0);
}

TEST(WeedEval, VegetationCallsTheCropWeed) {
  vision::PipelineConfig config = vision::default_pipeline_config();
  const WeedEvalRow row =
      evaluate_weed_source({synthetic_field()}, config, {}, one_row_of_four(), true);
  const double crop = 2 * 16 * 100;
  const double weed = 100 + 16;
  EXPECT_DOUBLE_EQ(row.scores.iou[1], 0.0);
  EXPECT_DOUBLE_EQ(row.scores.iou[2], weed / (weed + crop));
  EXPECT_DOUBLE_EQ(row.scores.pixel_accuracy[2], 1.0);
  EXPECT_DOUBLE_EQ(row.vegetation_iou, 1.0);
  // The crop rows make zones 0 and 2 sprayed although they hold no weed.
  EXPECT_DOUBLE_EQ(row.zones.clean_left_dry(), 1.0 / 3.0);
}

TEST(WeedEval, MasksThatAreNotClassIdsNameTheImage) {
  LabelledImage image = synthetic_field();
  image.mask.setTo(255, image.plant);
  try {
    evaluate_weed_source({image}, vision::default_pipeline_config(), {}, one_row_of_four(), true);
    FAIL() << "accepted a 0/255 plant mask as class ids";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("synthetic"), std::string::npos) << error.what();
  }
}

TEST(ImageIntervals, BracketTheFiguresAndCollapseForIdenticalImages) {
  WeedEvalRow row;
  row.rule.rows = 1;
  row.rule.cols = 1;
  row.rule.decision_threshold = 0.01;
  ConfusionMatrix perfect;
  perfect.counts[0][0] = 90;
  perfect.counts[2][2] = 10;
  ConfusionMatrix missed;  // every weed pixel called soil
  missed.counts[0][0] = 90;
  missed.counts[2][0] = 10;
  for (int i = 0; i < 10; ++i) {
    row.image_confusion.push_back(perfect);
    row.zone_samples.push_back({0.1, 0.1, 0.0});  // weedy and sprayed
  }
  ImageIntervals same = image_intervals(row);
  EXPECT_DOUBLE_EQ(same.weed_iou[0], 1.0);
  EXPECT_DOUBLE_EQ(same.weed_iou[1], 1.0);
  EXPECT_DOUBLE_EQ(same.recall[0], 1.0);
  for (int i = 0; i < 10; ++i) {
    row.image_confusion.push_back(missed);
    row.zone_samples.push_back({0.1, 0.0, 0.0});  // weedy and left dry
  }
  const ImageIntervals mixed = image_intervals(row);
  EXPECT_LT(mixed.weed_iou[0], 0.5);  // the whole set scores 0.5
  EXPECT_GT(mixed.weed_iou[1], 0.5);
  EXPECT_LT(mixed.recall[0], 0.5);
  EXPECT_GT(mixed.recall[1], 0.5);
  EXPECT_GT(mixed.recall[0], 0.1);
}

TEST(WeedEval, CropMarginIsAGroundDistanceAtTheImagesScale) {
  EXPECT_EQ(crop_margin_px_at(2.0, 0.3125, 3), 64);  // 20 mm at 0.3125 mm/px
  EXPECT_EQ(crop_margin_px_at(2.0, 2.0, 3), 10);
  EXPECT_EQ(crop_margin_px_at(2.0, 0.0, 3), 3);  // scale unknown: the fallback
}

TEST(WeedEval, ResamplingToACamerasScaleKeepsTheGroundAndTheClassIds) {
  LabelledImage image;
  image.name = "square";
  image.bgr = cv::Mat(120, 160, CV_8UC3, cv::Scalar(30, 60, 90));
  image.mask = cv::Mat::zeros(120, 160, CV_8UC1);
  image.mask(cv::Rect(40, 40, 40, 40)).setTo(1);   // crop
  image.mask(cv::Rect(100, 40, 20, 20)).setTo(2);  // weed
  image.plant = image.mask != 0;
  std::vector<LabelledImage> images{image};
  resample_to_scale(images, 0.25, 1.0);  // 40 mm x 30 mm of ground at 1 mm/px
  EXPECT_EQ(images[0].bgr.size(), cv::Size(40, 30));
  EXPECT_EQ(images[0].mask.size(), cv::Size(40, 30));
  EXPECT_EQ(images[0].plant.size(), cv::Size(40, 30));
  double lowest = 0, highest = 0;
  cv::minMaxLoc(images[0].mask, &lowest, &highest);
  EXPECT_EQ(highest, 2.0);                                // ids, not blends of them
  EXPECT_EQ(cv::countNonZero(images[0].mask == 1), 100);  // 10 mm x 10 mm
  EXPECT_EQ(cv::countNonZero(images[0].mask == 2), 25);
  EXPECT_EQ(cv::countNonZero(images[0].mask > 2), 0);
}

}  // namespace
}  // namespace weedspray::lab
