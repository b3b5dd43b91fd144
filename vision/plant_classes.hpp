// SPDX-License-Identifier: Apache-2.0
// Per-plant classification (the plants weed source): colour finds the plants at the frame's
// own resolution, the network, run at its coarser ground scale, only votes on which plants are
// crop. Plants are the vegetation grown by join_px: the pieces colour cuts a grass blade into
// join, and the soft leaf edge the colour threshold leaves out comes in. A plant the network calls
// neither crop nor weed takes the class the network sees within one of its pixels (a leaf edge
// beside the crop); with nothing near, it is a weed too small for the network when it has at least
// min_plant_px pixels, else a colour speck. Internal to vision/ (WeedClassifier owns one).
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace weedspray::vision {

class PlantClasses {
 public:
  // min_plant_px: the least unresolved plant that is weed; also the least weed-voted area
  // that stays weed inside a plant the network calls crop. join_px >= 0.
  PlantClasses(int min_plant_px, int join_px);

  // vegetation: CV_8UC1, non-zero = vegetation (the colour threshold's). network_classes: CV_8UC1
  // class ids (kClassSoil/kClassCrop/kClassWeed) at the network's resolution, covering the same
  // ground. Writes one class id per pixel into `classes` (CV_8UC1, vegetation's size).
  void classify(const cv::Mat& vegetation, const cv::Mat& network_classes, cv::Mat& classes);

  // The vegetation grown by join_px into `joined` (what classify calls plants).
  void join(const cv::Mat& vegetation, cv::Mat& joined) const;

 private:
  struct Votes {
    std::uint32_t pixels = 0;  // pixels of the plant
    std::uint32_t crop = 0;    // ... the network calls crop
    std::uint32_t weed = 0;
    std::uint32_t near_crop = 0;  // ... within one network pixel of its crop
    std::uint32_t near_weed = 0;
  };
  void map_to_network(cv::Size region, cv::Size network);
  void count_votes(const cv::Mat& vegetation, const cv::Mat& network_classes);
  void decide_plants();

  int min_plant_px_;
  cv::Mat join_kernel_, near_kernel_;
  cv::Mat joined_, labels_, near_crop_, near_weed_;
  cv::Size region_size_, network_size_;
  std::vector<int> network_column_;  // region column -> network column
  std::vector<int> network_row_;
  std::vector<Votes> votes_;               // per connected plant
  std::vector<std::uint8_t> plant_class_;  // per plant
  std::vector<std::uint8_t> keeps_weed_;   // per plant: crop, but weed where the network says so
};

}  // namespace weedspray::vision
