#include "lab/weed_model.hpp"

#include <cstdio>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <variant>

#include <opencv2/core.hpp>

#include "daemon/config/config.hpp"
#include "daemon/config/config_schema.hpp"
#include "daemon/config/vision_config.hpp"

namespace weedspray::lab {
namespace {

std::string read_file(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error(path.string() + ": cannot read");
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

// The text of the JSON object that follows "key": (OpenCV's JSON reader rejects the null
// values the rest of a training report may hold, so only this object is parsed).
std::string json_object_text(const std::string& json, const std::string& key,
                             const std::filesystem::path& path) {
  const auto at = json.find("\"" + key + "\"");
  const auto open = at == std::string::npos ? at : json.find('{', at);
  if (open == std::string::npos) {
    throw std::runtime_error(path.string() + ": no \"" + key + "\" object");
  }
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = open; i < json.size(); ++i) {
    const char c = json[i];
    if (in_string) {
      if (c == '\\') ++i;
      if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{') {
      ++depth;
    } else if (c == '}' && --depth == 0) {
      return json.substr(open, i - open + 1);
    }
  }
  throw std::runtime_error(path.string() + ": \"" + key + "\" object is not closed");
}

vision::DnnModelSpec parse_spec(const std::filesystem::path& path) {
  const std::string text = json_object_text(read_file(path), "spec", path);
  vision::DnnModelSpec spec;
  try {
    cv::FileStorage storage(
        text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_JSON);
    const cv::FileNode root = storage.root();
    const auto require = [&](const char* key) {
      const cv::FileNode node = root[key];
      if (node.empty()) throw std::runtime_error(path.string() + ": spec has no " + key);
      return node;
    };
    spec.input_width = static_cast<int>(require("input_width"));
    spec.input_height = static_cast<int>(require("input_height"));
    const cv::FileNode mean = require("mean_rgb");
    if (!mean.isSeq() || mean.size() != 3) {
      throw std::runtime_error(path.string() + ": spec mean_rgb must list 3 numbers");
    }
    for (int c = 0; c < 3; ++c) spec.mean_rgb[c] = static_cast<double>(mean[c]);
    spec.scale = static_cast<double>(require("scale"));
    spec.rgb = static_cast<int>(require("rgb")) != 0;
    spec.classes.clear();
    for (const cv::FileNode& name : require("classes")) spec.classes.push_back(name.string());
    spec.soil_class = static_cast<int>(require("soil_class"));
    spec.crop_class = static_cast<int>(require("crop_class"));
    spec.weed_class = static_cast<int>(require("weed_class"));
  } catch (const cv::Exception& error) {
    throw std::runtime_error(path.string() + ": cannot parse the spec (" + error.what() + ")");
  }
  if (auto problem = vision::validate_dnn_spec(spec)) {
    throw std::runtime_error(path.string() + ": " + *problem);
  }
  return spec;
}

}  // namespace

WeedModel read_weed_model(const std::filesystem::path& onnx_path) {
  WeedModel model;
  model.path = onnx_path;
  const std::string bytes = read_file(onnx_path);
  if (bytes.empty()) throw std::runtime_error(onnx_path.string() + ": empty model file");
  model.onnx.assign(bytes.begin(), bytes.end());
  std::filesystem::path spec_path = onnx_path;
  spec_path.replace_extension(".json");
  if (std::filesystem::exists(spec_path)) {
    model.spec = parse_spec(spec_path);
    model.spec_from_json = true;
  }
  return model;
}

DaemonVisionSetup read_daemon_vision_setup(const std::filesystem::path& config_file) {
  const daemon::Config config = daemon::load_config(config_file);
  if (config.cameras.empty()) throw std::runtime_error(config_file.string() + ": no [[camera]]");
  DaemonVisionSetup setup;
  setup.pipeline = daemon::pipeline_config(config, config.cameras.front());
  if (config.model) setup.onnx = config.model->onnx;
  setup.decision_threshold = config.spray.decision_threshold;
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

vision::WeedSource parse_weed_source_option(const std::string& option, const std::string& value) {
  if (const auto source = vision::parse_weed_source(value)) return *source;
  std::string names;
  for (std::string_view name : vision::weed_source_names()) {
    names += (names.empty() ? "" : ", ") + std::string(name);
  }
  throw std::runtime_error(option + " " + value + ": unknown (one of " + names + ")");
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
