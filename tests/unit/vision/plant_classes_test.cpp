// SPDX-License-Identifier: Apache-2.0
// The plants weed source's per-plant rule: colour plants at full resolution, classified by a
// coarser network's votes.
#include "vision/plant_classes.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "vision/weed_source.hpp"

namespace weedspray::vision {
namespace {

constexpr int kSide = 40;     // region pixels
constexpr int kNetwork = 10;  // network pixels: one covers 4 x 4 region pixels
constexpr int kMinPlant = 20;

struct Scene {
  cv::Mat vegetation = cv::Mat::zeros(kSide, kSide, CV_8UC1);
  cv::Mat network = cv::Mat(kNetwork, kNetwork, CV_8UC1, cv::Scalar(kClassSoil));
  void plant(int x, int y, int width, int height) {
    vegetation(cv::Rect(x, y, width, height)).setTo(255);
  }
  // Network pixels (in network coordinates) called `id`.
  void network_says(int x, int y, int width, int height, std::uint8_t id) {
    network(cv::Rect(x, y, width, height)).setTo(id);
  }
  cv::Mat classify(int join_px = 0) {
    PlantClasses plants(kMinPlant, join_px);
    cv::Mat classes;
    plants.classify(vegetation, network, classes);
    return classes;
  }
};

int count(const cv::Mat& classes, cv::Rect rect, std::uint8_t id) {
  return cv::countNonZero(classes(rect) == id);
}

TEST(PlantClasses, APlantTheNetworkCannotSeeIsWeedAndAColourSpeckIsNot) {
  Scene scene;
  scene.plant(2, 2, 5, 5);    // 25 px, network soil: a seedling too small for it
  scene.plant(30, 30, 2, 2);  // 4 px: a speck
  const cv::Mat classes = scene.classify();
  EXPECT_EQ(count(classes, {2, 2, 5, 5}, kClassWeed), 25);
  EXPECT_EQ(count(classes, {30, 30, 2, 2}, kClassSoil), 4);
}

TEST(PlantClasses, AWholePlantFollowsTheNetworksMajorityEdgesIncluded) {
  Scene scene;
  scene.plant(4, 4, 14, 14);                   // network pixels 1..4 of it
  scene.network_says(1, 1, 3, 3, kClassCrop);  // region 4..15: most of the plant
  scene.network_says(4, 1, 1, 1, kClassWeed);  // a corner the network gets wrong
  const cv::Mat classes = scene.classify();
  // 196 px, of which 144 crop votes and 8 weed votes (< kMinPlant): all crop, the edge the
  // network calls soil and the mistaken corner included.
  EXPECT_EQ(count(classes, {4, 4, 14, 14}, kClassCrop), 14 * 14);
}

TEST(PlantClasses, AWeedGrownIntoACropPlantStaysWeedWhereTheNetworkSeesIt) {
  Scene scene;
  scene.plant(4, 4, 24, 24);
  scene.network_says(1, 1, 6, 6, kClassCrop);
  scene.network_says(5, 5, 2, 2, kClassWeed);  // region 20..27: 64 px, a plant's size
  const cv::Mat classes = scene.classify();
  EXPECT_EQ(count(classes, {20, 20, 8, 8}, kClassWeed), 64);
  EXPECT_EQ(count(classes, {4, 4, 16, 16}, kClassCrop), 256);
}

TEST(PlantClasses, ASpeckBesideTheNetworksCropOrWeedTakesItsClass) {
  Scene scene;
  scene.network_says(1, 1, 2, 2, kClassCrop);  // region 4..11
  scene.plant(12, 5, 2, 2);                    // network pixel 3: one beside the crop
  scene.network_says(7, 7, 2, 2, kClassWeed);  // region 28..35
  scene.plant(36, 30, 2, 2);                   // network pixel 9: beside the weed
  const cv::Mat classes = scene.classify();
  EXPECT_EQ(count(classes, {12, 5, 2, 2}, kClassCrop), 4);
  EXPECT_EQ(count(classes, {36, 30, 2, 2}, kClassWeed), 4);
}

TEST(PlantClasses, PiecesCloserThanTheJoinAreOnePlant) {
  Scene scene;
  scene.plant(10, 10, 3, 3);  // 9 px each, 2 px apart: specks alone
  scene.plant(15, 10, 3, 3);
  EXPECT_EQ(count(scene.classify(0), {10, 10, 8, 3}, kClassWeed), 0);
  // Joined (and grown by the join), one plant of more than kMinPlant pixels: weed.
  const cv::Mat joined = scene.classify(1);
  EXPECT_EQ(count(joined, {10, 10, 3, 3}, kClassWeed), 9);
  EXPECT_EQ(count(joined, {15, 10, 3, 3}, kClassWeed), 9);
}

TEST(PlantClasses, TheClassMapHasTheVegetationsSizeWhateverTheNetworksSize) {
  Scene scene;
  scene.plant(0, 0, kSide, kSide);
  scene.network = cv::Mat(7, 13, CV_8UC1, cv::Scalar(kClassCrop));
  const cv::Mat classes = scene.classify();
  EXPECT_EQ(classes.size(), cv::Size(kSide, kSide));
  EXPECT_EQ(cv::countNonZero(classes == kClassCrop), kSide * kSide);
}

}  // namespace
}  // namespace weedspray::vision
