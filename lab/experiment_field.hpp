// SPDX-License-Identifier: Apache-2.0
// A field for the savings experiment from labelled crop/weed photos (class-id masks: 0 soil,
// 1 crop, 2 weed): each image cut into the wheat paper's layout of 2 zone rows along travel x 4
// nozzle columns, images laid one after another along a track.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <opencv2/core.hpp>

#include "lab/experiments/experiments.hpp"
#include "lab/vision_dataset.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::lab {

inline constexpr int kFieldZoneRows = 2;
inline constexpr int kFieldNozzles = 4;

struct LabelledField {
  // Zones in track order: image i contributes its near (bottom) row, then its far row.
  std::vector<std::array<double, kFieldNozzles>> weed_density;  // what the sprayer acts on
  std::vector<std::array<lab::experiments::ZoneTruth, kFieldNozzles>> truth;
};

// The true weed and crop shares of each zone of a class-id mask (same zone bounds as the
// vision pipeline's grid), in track order. Throws std::invalid_argument on an empty mask.
std::vector<std::array<lab::experiments::ZoneTruth, kFieldNozzles>> mask_zone_truth(
    const cv::Mat& class_mask);

// The field of the labelled photos in their order (LabelledImage::mask: class ids). The weed
// density the sprayer acts on is the true weed share when `source` is nullopt (the best any
// detector can do), else what the vision pipeline configured by `source` reports (rows and
// cols are set here; dnn/hybrid need model_onnx). Throws std::runtime_error naming the image
// the pipeline fails on, std::invalid_argument on a bad configuration or mask.
LabelledField labelled_field(const std::vector<LabelledImage>& images,
                             const std::optional<vision::PipelineConfig>& source,
                             std::span<const std::uint8_t> model_onnx = {});

}  // namespace weedspray::lab
