// SPDX-License-Identifier: Apache-2.0
// A weed model's description: NAME.json beside NAME.onnx (tools/train/train.py writes it),
// holding the spec the network must be fed by, the ground scale it learnt at and its licence.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "vision/weed_source.hpp"

namespace weedspray::daemon {

struct ModelDescription {
  std::filesystem::path path;  // the JSON read
  vision::DnnModelSpec spec;
  std::string licence;  // empty when the JSON names none
  // Ground size of one pixel of the photos it was trained and validated on
  // (training.dataset_mm_per_px); 0 = not stated.
  double dataset_mm_per_px = 0.0;
};

// The JSON path beside an ONNX file: same folder and stem, ".json".
[[nodiscard]] std::filesystem::path description_path(const std::filesystem::path& onnx);

// Reads `json`: the "spec" object (input_width, input_height, mean_rgb, scale, rgb, classes,
// soil_class, crop_class, weed_class; optional ground_mm_per_px (null = unknown), stride,
// input_channels), "licence" and training.dataset_mm_per_px. nullopt when the file does not exist;
// throws std::runtime_error naming the file and the key when it cannot be read or a key is missing
// or of the wrong type.
[[nodiscard]] std::optional<ModelDescription> read_model_description(
    const std::filesystem::path& json);

}  // namespace weedspray::daemon
