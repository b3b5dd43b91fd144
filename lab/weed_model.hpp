// SPDX-License-Identifier: Apache-2.0
// The weed model and pipeline settings the lab's vision commands run: from --model FILE (its
// spec from FILE's .json sibling, as tools/train writes it) or from a daemon configuration.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "vision/pipeline.hpp"

namespace weedspray::lab {

struct WeedModel {
  std::filesystem::path path;
  std::vector<std::uint8_t> onnx;
  vision::DnnModelSpec spec;  // from the .json sibling; DnnModelSpec's defaults without one
  bool spec_from_json = false;
  double dataset_mm_per_px = 0.0;  // the training photos' ground scale; 0 = not stated
};

// Reads FILE and, when there is one, FILE with the extension .json as the daemon reads it
// (daemon/config/model_description.hpp). Throws std::runtime_error naming the file.
WeedModel read_weed_model(const std::filesystem::path& onnx_path);

// A daemon configuration file as the lab runs it: the first camera's pipeline (index,
// threshold, region, grid, weed source, row band and margin converted to pixels), the model
// it loads (empty unless the weed source needs one) and the spray decision threshold.
struct DaemonVisionSetup {
  vision::PipelineConfig pipeline;
  std::vector<std::uint8_t> onnx;
  double decision_threshold = 0;
  double dataset_mm_per_px = 0;  // the model's training photos' ground scale; 0 = not stated
  double crop_margin_cm = 0;     // vision.crop_margin_cm, to convert at the images' own scale
  double min_plant_cm2 = 0;      // vision.min_plant_cm2, likewise
};
DaemonVisionSetup read_daemon_vision_setup(const std::filesystem::path& config_file);

// spray.decision_threshold's default in the daemon's key table (the one place it is set).
double default_decision_threshold();

// Every weed source's name, comma-separated, for help texts and errors.
std::string weed_source_list();

// "vegetation" ... -> WeedSource; std::runtime_error naming `option` and the choices.
vision::WeedSource parse_weed_source_option(const std::string& option, const std::string& value);

// "2x4" -> rows, cols; std::runtime_error naming `option`.
void parse_grid_option(const std::string& option, const std::string& value, int& rows, int& cols);

}  // namespace weedspray::lab
