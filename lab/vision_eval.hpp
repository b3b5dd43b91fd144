// SPDX-License-Identifier: Apache-2.0
// vision-eval: every index x threshold combination against hand-labelled masks (the UGV
// paper's Table 6 columns plus IoU against ground truth).
#pragma once

#include <span>
#include <vector>

#include "lab/vision_dataset.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::lab {

struct EvalRow {
  vision::VegetationIndex index{};
  vision::ThresholdMethod threshold{};
  double mean_iou = 0;         // plant IoU of the mask against the labels
  double mean_threshold = 0;   // on the index's 8-bit scale
  double threshold_error = 0;  // eps: mean |T_otsu - T| on the same index
  double precision_pct = 0;    // rho: 100 - mean |veg% - veg% of Otsu|
  double ms_per_image = 0;     // pipeline time (index + histogram + threshold + densities)
};

// Runs the vision pipeline (one zone, whole frame) configured from `base` with each index and
// threshold over all images.
std::vector<EvalRow> evaluate_combinations(const std::vector<LabelledImage>& images,
                                           std::span<const vision::VegetationIndex> indices,
                                           std::span<const vision::ThresholdMethod> methods,
                                           const vision::PipelineConfig& base);

// Plant IoU of (index > threshold) against the labels; 1 when both are empty.
double plant_iou(const vision::ImageView& index_image, int threshold, const cv::Mat& plant);

// Upper bounds for one index: the mean IoU with the best threshold chosen per image
// (oracle) and with the best single threshold shared by all images (returned in best_fixed).
struct IndexBounds {
  double oracle_iou = 0;
  double best_fixed_iou = 0;
  int best_fixed = 0;
};
IndexBounds index_bounds(const std::vector<LabelledImage>& images, vision::VegetationIndex index);

}  // namespace weedspray::lab
