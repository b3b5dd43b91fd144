// SPDX-License-Identifier: Apache-2.0
// Crop / weed / soil metrics of class maps against class-id masks: per-class IoU, MIoU and MPA
// as the wheat paper defines them (over the whole confusion matrix of a set of images), and
// the sprayer's zone trade-off (weedy zones sprayed, weed-free zones left dry).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <opencv2/core.hpp>

namespace weedspray::lab {

inline constexpr int kClassCount = 3;  // 0 soil, 1 crop, 2 weed

struct ConfusionMatrix {
  std::array<std::array<std::uint64_t, kClassCount>, kClassCount> counts{};  // [truth][predicted]
  // truth and predicted: CV_8UC1 of the same size holding class ids < kClassCount.
  void add(const cv::Mat& truth, const cv::Mat& predicted);
};

struct ClassScores {
  std::array<double, kClassCount> iou{};  // TP / (TP + FP + FN), 1 if the class is absent
  std::array<double, kClassCount> pixel_accuracy{};  // TP / truth pixels, 1 if the class is absent
  double miou = 0;                                   // mean of iou over the classes
  double mpa = 0;                                    // mean of pixel_accuracy over the classes
};
ClassScores class_scores(const ConfusionMatrix& confusion);

// Zones of a rows x cols grid: weedy when at least weedy_share of the zone is weed in the
// truth, clean (weed-free for the sprayer) otherwise; a clean zone is crop-only when at least
// weedy_share of it is crop (what a sprayer that hits the crop wastes herbicide on), bare
// otherwise. Sprayed when the pipeline's weed density reaches the decision threshold (the rate
// law's rule: density > 0 and density >= threshold).
struct ZoneRule {
  int rows = 2;
  int cols = 4;
  double weedy_share = 0.005;
  double decision_threshold = 0.01;
};

struct ZoneTally {
  int weedy = 0;
  int weedy_sprayed = 0;
  int clean = 0;
  int clean_dry = 0;
  int crop_only = 0;  // clean zones with crop
  int crop_only_dry = 0;
  int bare = 0;  // clean zones without crop
  int bare_dry = 0;
  double recall() const { return share(weedy_sprayed, weedy); }
  double clean_left_dry() const { return share(clean_dry, clean); }
  double crop_only_left_dry() const { return share(crop_only_dry, crop_only); }
  double bare_left_dry() const { return share(bare_dry, bare); }

 private:
  static double share(int part, int whole) {
    return whole == 0 ? 1.0 : static_cast<double>(part) / whole;
  }
};

bool would_spray(double weed_density, double decision_threshold);

// One zone of one image: its true weed share and the pipeline's weed density.
struct ZoneSample {
  double true_weed_share = 0;
  double weed_density = 0;
  double true_crop_share = 0;
};

// The zones of one image: truth (class ids over the zones' region) and the pipeline's weed
// density per zone (row-major, rows * cols), appended to `samples`.
void add_zone_samples(const cv::Mat& truth, std::span<const double> weed_density, int rows,
                      int cols, std::vector<ZoneSample>& samples);

ZoneTally tally_zones(std::span<const ZoneSample> samples, const ZoneRule& rule);

// Zone (row, col) of a rows x cols grid over a size image, cut as vision::Pipeline cuts it.
cv::Rect zone_rect(int row, int col, int rows, int cols, cv::Size size);

}  // namespace weedspray::lab
