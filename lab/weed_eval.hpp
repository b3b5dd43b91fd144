// SPDX-License-Identifier: Apache-2.0
// Evaluation of the weed sources (vegetation, inter_row, dnn, hybrid) against labelled images:
// class metrics and the zone trade-off against class-id masks, vegetation IoU against any.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "lab/class_metrics.hpp"
#include "lab/vision_dataset.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::lab {

struct WeedEvalRow {
  vision::WeedSource source{};
  ClassScores scores;                    // with class masks
  ZoneTally zones;                       // with class masks, at the rule's decision threshold
  std::vector<ZoneSample> zone_samples;  // with class masks: every zone of every image
  double vegetation_iou = 0;  // mean over images of (crop or weed) against plant (non-zero)
  double ms_per_image = 0;    // Pipeline::process, index to zone densities
  std::vector<ConfusionMatrix> image_confusion;  // with class masks: one per image
  ZoneRule rule;                                 // zone_samples hold rows x cols per image
};

// 95 % intervals of the figures over images: the images resampled with replacement (a seeded
// bootstrap of 1000 draws), each draw scored whole as the row is; [low, high].
struct ImageIntervals {
  std::array<double, 2> miou{}, crop_iou{}, weed_iou{};
  std::array<double, 2> recall{}, crop_only_left_dry{}, bare_left_dry{};
};
ImageIntervals image_intervals(const WeedEvalRow& row);

// The hybrid's crop margin (a ground distance) in pixels of images image_mm_per_px each, as
// the daemon converts vision.crop_margin_cm for a camera; fallback_px where the scale is unknown.
int crop_margin_px_at(double crop_margin_cm, double image_mm_per_px, int fallback_px);

// The images and masks as a camera of frame_mm_per_px would see the same ground: images
// averaged (INTER_AREA, or INTER_LINEAR when enlarged), masks' ids kept (nearest).
void resample_to_scale(std::vector<LabelledImage>& images, double image_mm_per_px,
                       double frame_mm_per_px);

// Runs `config` (its weed_source, with the rule's zone grid) over every image, each one a
// fresh start for the row tracker (the photos are not a sequence). With class_masks, the
// masks hold class ids (0 soil, 1 crop, 2 weed) and give scores and zones; a mask with other
// ids is a std::runtime_error naming the image.
WeedEvalRow evaluate_weed_source(const std::vector<LabelledImage>& images,
                                 vision::PipelineConfig config,
                                 std::span<const std::uint8_t> model_onnx, const ZoneRule& rule,
                                 bool class_masks);

// The pipeline's class map (kClassSoil / kClassCrop / kClassWeed) at the region's size.
cv::Mat class_map_at_region_size(vision::Pipeline& pipeline);

}  // namespace weedspray::lab
