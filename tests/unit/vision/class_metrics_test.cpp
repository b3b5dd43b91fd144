// SPDX-License-Identifier: Apache-2.0
// The lab's crop/weed metrics against masks computed by hand.
#include "lab/class_metrics.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace weedspray::lab {
namespace {

cv::Mat mask(int rows, int cols, std::vector<std::uint8_t> ids) {
  return cv::Mat(rows, cols, CV_8UC1, ids.data()).clone();
}

// 2x4 truth and prediction (0 soil, 1 crop, 2 weed):
//   truth      predicted
//   0 0 1 1    0 1 1 1
//   0 2 2 1    0 2 0 1
// soil:  truth 3, predicted 3, hit 2 -> IoU 2/4, accuracy 2/3
// crop:  truth 3, predicted 4, hit 3 -> IoU 3/4, accuracy 1
// weed:  truth 2, predicted 1, hit 1 -> IoU 1/2, accuracy 1/2
TEST(ClassMetrics, IouMiouAndMpaFromTheConfusionMatrix) {
  const cv::Mat truth = mask(2, 4, {0, 0, 1, 1, 0, 2, 2, 1});
  const cv::Mat predicted = mask(2, 4, {0, 1, 1, 1, 0, 2, 0, 1});
  ConfusionMatrix confusion;
  confusion.add(truth, predicted);
  EXPECT_EQ(confusion.counts[0][1], 1u);
  EXPECT_EQ(confusion.counts[2][0], 1u);
  const ClassScores scores = class_scores(confusion);
  EXPECT_DOUBLE_EQ(scores.iou[0], 2.0 / 4.0);
  EXPECT_DOUBLE_EQ(scores.iou[1], 3.0 / 4.0);
  EXPECT_DOUBLE_EQ(scores.iou[2], 1.0 / 2.0);
  EXPECT_DOUBLE_EQ(scores.miou, (2.0 / 4.0 + 3.0 / 4.0 + 1.0 / 2.0) / 3.0);
  EXPECT_DOUBLE_EQ(scores.pixel_accuracy[0], 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(scores.pixel_accuracy[1], 1.0);
  EXPECT_DOUBLE_EQ(scores.pixel_accuracy[2], 1.0 / 2.0);
  EXPECT_DOUBLE_EQ(scores.mpa, (2.0 / 3.0 + 1.0 + 1.0 / 2.0) / 3.0);
}

TEST(ClassMetrics, ImagesAccumulateBeforeTheRatios) {
  // Per-image IoUs of weed would be 1 and 0; over the set it is 1 / 2.
  ConfusionMatrix confusion;
  confusion.add(mask(1, 2, {2, 0}), mask(1, 2, {2, 0}));
  confusion.add(mask(1, 2, {2, 0}), mask(1, 2, {0, 0}));
  EXPECT_DOUBLE_EQ(class_scores(confusion).iou[2], 1.0 / 2.0);
}

TEST(ClassMetrics, VegetationAsWeedScoresZeroCrop) {
  const cv::Mat truth = mask(1, 4, {0, 1, 1, 2});
  const cv::Mat everything_green_is_weed = mask(1, 4, {0, 2, 2, 2});
  ConfusionMatrix confusion;
  confusion.add(truth, everything_green_is_weed);
  const ClassScores scores = class_scores(confusion);
  EXPECT_DOUBLE_EQ(scores.iou[1], 0.0);
  EXPECT_DOUBLE_EQ(scores.iou[2], 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(scores.iou[0], 1.0);
}

TEST(ClassMetrics, OutOfRangeIdsAndSizesAreRejected) {
  ConfusionMatrix confusion;
  EXPECT_THROW(confusion.add(mask(1, 2, {0, 3}), mask(1, 2, {0, 0})), std::invalid_argument);
  EXPECT_THROW(confusion.add(mask(1, 2, {0, 0}), mask(2, 1, {0, 0})), std::invalid_argument);
}

TEST(ZoneTally, WeedyZonesSprayedAndCleanZonesLeftDry) {
  // 2x4 grid of 10x10 zones over a 20x40 truth; one weed pixel (1 % of a zone) in zones 0
  // and 5, the others weed-free.
  cv::Mat truth(20, 40, CV_8UC1, cv::Scalar(0));
  truth.at<std::uint8_t>(3, 3) = 2;    // zone 0
  truth.at<std::uint8_t>(15, 15) = 2;  // zone 5
  truth.at<std::uint8_t>(5, 25) = 1;   // crop in zone 2: not weed
  ZoneRule rule;
  rule.rows = 2;
  rule.cols = 4;
  rule.weedy_share = 0.01;
  rule.decision_threshold = 0.02;
  // Sprayed: zones 0 (0.05), 2 (0.02: equal to the threshold sprays); zone 5 (0.019) dry.
  const std::vector<double> density = {0.05, 0.0, 0.02, 0.0, 0.0, 0.019, 0.0, 0.0};
  std::vector<ZoneSample> samples;
  add_zone_samples(truth, density, rule.rows, rule.cols, samples);
  ASSERT_EQ(samples.size(), 8u);
  EXPECT_DOUBLE_EQ(samples[0].true_weed_share, 0.01);
  EXPECT_DOUBLE_EQ(samples[2].true_weed_share, 0.0);
  const ZoneTally tally = tally_zones(samples, rule);
  EXPECT_EQ(tally.weedy, 2);
  EXPECT_EQ(tally.weedy_sprayed, 1);
  EXPECT_EQ(tally.clean, 6);
  EXPECT_EQ(tally.clean_dry, 5);
  EXPECT_DOUBLE_EQ(tally.recall(), 0.5);
  EXPECT_DOUBLE_EQ(tally.clean_left_dry(), 5.0 / 6.0);
  // Of the clean zones, zone 2 holds crop (1 %) and was sprayed: the crop hit; the 5 bare ones
  // stayed dry.
  EXPECT_DOUBLE_EQ(samples[2].true_crop_share, 0.01);
  EXPECT_EQ(tally.crop_only, 1);
  EXPECT_EQ(tally.crop_only_dry, 0);
  EXPECT_DOUBLE_EQ(tally.crop_only_left_dry(), 0.0);
  EXPECT_EQ(tally.bare, 5);
  EXPECT_DOUBLE_EQ(tally.bare_left_dry(), 1.0);

  // A zone under the weedy share is clean: 1 px of 100 is not 2 %.
  rule.weedy_share = 0.02;
  const ZoneTally strict = tally_zones(samples, rule);
  EXPECT_EQ(strict.weedy, 0);
  EXPECT_DOUBLE_EQ(strict.recall(), 1.0);
  EXPECT_EQ(strict.clean, 8);
}

TEST(ZoneTally, ZeroDensityNeverSprays) {
  EXPECT_FALSE(would_spray(0.0, 0.0));
  EXPECT_TRUE(would_spray(1e-6, 0.0));
  EXPECT_FALSE(would_spray(0.009, 0.01));
  EXPECT_TRUE(would_spray(0.01, 0.01));
}

}  // namespace
}  // namespace weedspray::lab
