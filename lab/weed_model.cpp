// SPDX-License-Identifier: Apache-2.0
#include "lab/weed_model.hpp"

#include <cstdio>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <variant>

#include "daemon/config/config.hpp"
#include "daemon/config/config_schema.hpp"
#include "daemon/config/model_description.hpp"
#include "daemon/config/vision_config.hpp"

namespace weedspray::lab {
namespace {

std::string read_file(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error(path.string() + ": cannot read");
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

}  // namespace

WeedModel read_weed_model(const std::filesystem::path& onnx_path) {
  WeedModel model;
  model.path = onnx_path;
  const std::string bytes = read_file(onnx_path);
  if (bytes.empty()) throw std::runtime_error(onnx_path.string() + ": empty model file");
  model.onnx.assign(bytes.begin(), bytes.end());
  if (auto description = daemon::read_model_description(daemon::description_path(onnx_path))) {
    model.spec = description->spec;
    model.dataset_mm_per_px = description->dataset_mm_per_px;
    model.spec_from_json = true;
  }
  return model;
}

DaemonVisionSetup read_daemon_vision_setup(const std::filesystem::path& config_file) {
  const daemon::Config config = daemon::load_config(config_file);
  if (config.cameras.empty()) throw std::runtime_error(config_file.string() + ": no [[camera]]");
  DaemonVisionSetup setup;
  setup.pipeline = daemon::pipeline_config(config, config.cameras.front());
  if (config.model) {
    setup.onnx = config.model->onnx;
    setup.dataset_mm_per_px = config.model->dataset_mm_per_px;
  }
  setup.decision_threshold = config.spray.decision_threshold;
  setup.crop_margin_cm = config.vision.crop_margin_cm;
  setup.min_plant_cm2 = config.vision.min_plant_cm2;
  return setup;
}

double default_decision_threshold() {
  for (const auto& key : daemon::config_keys()) {
    if (key.full_name() == "spray.decision_threshold") {
      return std::get<double>(key.default_value);
    }
  }
  throw std::logic_error("daemon key table has no spray.decision_threshold");
}

std::string weed_source_list() {
  std::string names;
  for (std::string_view name : vision::weed_source_names()) {
    names += (names.empty() ? "" : ", ") + std::string(name);
  }
  return names;
}

vision::WeedSource parse_weed_source_option(const std::string& option, const std::string& value) {
  if (const auto source = vision::parse_weed_source(value)) return *source;
  throw std::runtime_error(option + " " + value + ": unknown (one of " + weed_source_list() + ")");
}

void parse_grid_option(const std::string& option, const std::string& value, int& rows, int& cols) {
  char separator = 0;
  char extra = 0;
  if (std::sscanf(value.c_str(), "%d%c%d%c", &rows, &separator, &cols, &extra) != 3 ||
      (separator != 'x' && separator != 'X') || rows < 1 || cols < 1) {
    throw std::runtime_error(option + " " + value + ": expected ROWSxCOLS, e.g. 2x4");
  }
}

}  // namespace weedspray::lab
