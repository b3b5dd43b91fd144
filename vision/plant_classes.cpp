// SPDX-License-Identifier: Apache-2.0
#include "vision/plant_classes.hpp"

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "vision/weed_source.hpp"

namespace weedspray::vision {

namespace {
// Per-plant tables reserved up front, so that they keep their capacity from frame to frame
// (OpenCV's labelling still allocates its own work buffers each frame, as the network does).
constexpr std::size_t kReservedPlants = 1 << 16;

cv::Mat disc(int radius_px) {
  return cv::getStructuringElement(cv::MORPH_ELLIPSE,
                                   cv::Size(2 * radius_px + 1, 2 * radius_px + 1));
}
}  // namespace

PlantClasses::PlantClasses(int min_plant_px, int join_px)
    : min_plant_px_(min_plant_px), near_kernel_(disc(1)) {
  if (join_px > 0) join_kernel_ = disc(join_px);
  votes_.reserve(kReservedPlants);
  plant_class_.reserve(kReservedPlants);
  keeps_weed_.reserve(kReservedPlants);
}

void PlantClasses::map_to_network(cv::Size region, cv::Size network) {
  if (region == region_size_ && network == network_size_) return;
  region_size_ = region;
  network_size_ = network;
  network_column_.resize(static_cast<std::size_t>(region.width));
  network_row_.resize(static_cast<std::size_t>(region.height));
  // The pixel centre's place in the network's image, which covers the same ground.
  for (int x = 0; x < region.width; ++x) {
    network_column_[x] =
        std::min(network.width - 1, (2 * x + 1) * network.width / (2 * region.width));
  }
  for (int y = 0; y < region.height; ++y) {
    network_row_[y] =
        std::min(network.height - 1, (2 * y + 1) * network.height / (2 * region.height));
  }
}

void PlantClasses::count_votes(const cv::Mat& vegetation, const cv::Mat& network_classes) {
  const cv::Size size = vegetation.size();
  for (int y = 0; y < size.height; ++y) {
    const std::uint8_t* green = vegetation.ptr<std::uint8_t>(y);
    const int* label = labels_.ptr<int>(y);
    const int network_y = network_row_[y];
    const std::uint8_t* network = network_classes.ptr<std::uint8_t>(network_y);
    const std::uint8_t* near_crop = near_crop_.ptr<std::uint8_t>(network_y);
    const std::uint8_t* near_weed = near_weed_.ptr<std::uint8_t>(network_y);
    for (int x = 0; x < size.width; ++x) {
      if (green[x] == 0) continue;
      const int network_x = network_column_[x];
      Votes& plant = votes_[static_cast<std::size_t>(label[x])];
      ++plant.pixels;
      plant.crop += network[network_x] == kClassCrop;
      plant.weed += network[network_x] == kClassWeed;
      plant.near_crop += near_crop[network_x] != 0;
      plant.near_weed += near_weed[network_x] != 0;
    }
  }
}

void PlantClasses::decide_plants() {
  const auto min_plant = static_cast<std::uint32_t>(min_plant_px_);
  for (std::size_t i = 1; i < votes_.size(); ++i) {
    const Votes& plant = votes_[i];
    bool crop = plant.crop > plant.weed;
    if (plant.crop == 0 && plant.weed == 0) {  // the network sees soil: too small for it
      crop = plant.near_crop > plant.near_weed;
      if (!crop && plant.near_weed == 0 && plant.pixels < min_plant) continue;  // a speck
    }
    plant_class_[i] = crop ? kClassCrop : kClassWeed;
    // A weed grown into a crop plant joins it; a plant-sized weed vote keeps that part weed.
    keeps_weed_[i] = crop && plant.weed >= min_plant;
  }
}

void PlantClasses::join(const cv::Mat& vegetation, cv::Mat& joined) const {
  if (join_kernel_.empty()) {
    vegetation.copyTo(joined);
  } else {
    cv::dilate(vegetation, joined, join_kernel_);
  }
}

void PlantClasses::classify(const cv::Mat& vegetation, const cv::Mat& network_classes,
                            cv::Mat& classes) {
  const cv::Size size = vegetation.size();
  map_to_network(size, network_classes.size());
  join(vegetation, joined_);
  const int plants = cv::connectedComponents(joined_, labels_, 8, CV_32S);
  cv::compare(network_classes, kClassCrop, near_crop_, cv::CMP_EQ);
  cv::compare(network_classes, kClassWeed, near_weed_, cv::CMP_EQ);
  cv::dilate(near_crop_, near_crop_, near_kernel_);
  cv::dilate(near_weed_, near_weed_, near_kernel_);

  votes_.assign(static_cast<std::size_t>(plants), Votes{});
  count_votes(joined_, network_classes);
  plant_class_.assign(static_cast<std::size_t>(plants), kClassSoil);
  keeps_weed_.assign(static_cast<std::size_t>(plants), 0);
  decide_plants();

  classes.create(size, CV_8UC1);
  for (int y = 0; y < size.height; ++y) {
    const int* label = labels_.ptr<int>(y);
    const std::uint8_t* network = network_classes.ptr<std::uint8_t>(network_row_[y]);
    std::uint8_t* out = classes.ptr<std::uint8_t>(y);
    for (int x = 0; x < size.width; ++x) {
      const auto i = static_cast<std::size_t>(label[x]);
      out[x] = keeps_weed_[i] && network[network_column_[x]] == kClassWeed ? kClassWeed
                                                                           : plant_class_[i];
    }
  }
}

}  // namespace weedspray::vision
