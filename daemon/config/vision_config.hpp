// SPDX-License-Identifier: Apache-2.0
// Configuration -> the vision library's pipeline for each camera, and the weed model those
// pipelines are built from (found, read and checked once, when the configuration is loaded).
#pragma once

#include <filesystem>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/config/config_loader.hpp"
#include "daemon/config/model_loading.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::daemon {

// Ground size of one pixel of a camera's frame at the image centre, across travel, in mm:
// camera.ground_mm_per_px, or from its mount height, tilt and vertical field of view.
[[nodiscard]] double camera_ground_mm_per_px(const CameraSection& camera);

// The vision pipeline of `camera`: index, threshold, zone grid and weed source, with the
// ground distances of [vision] (row_band_cm, crop_margin_cm) converted for this camera, and
// the loaded model's spec (config.model) with the camera's ground scale.
// `model` null: config.model; both null: the spec of the model_* keys.
[[nodiscard]] vision::PipelineConfig pipeline_config(const Config& config,
                                                     const CameraSection& camera,
                                                     const LoadedModel* model = nullptr);

// One line per camera saying how its frames meet the weed model: "camera[0]: 1.01 mm/px ->
// weed-peanut.onnx (0.94 mm/px, CC BY-SA 4.0 ...): network input 1376x864"; empty when the weed
// source needs no model.
[[nodiscard]] std::vector<std::string> describe_model_use(const Config& config);

// Checks the weed source keys of a loaded configuration and, when the source needs a model,
// reads it and builds every camera's pipeline once (one forward pass): null for sources
// without a model. Throws VisionKeyError.
[[nodiscard]] std::shared_ptr<const LoadedModel> check_weed_source(const Config& config);

}  // namespace weedspray::daemon
