// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/model_description.hpp"

#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace weedspray::daemon {
namespace {

using nlohmann::json;

[[noreturn]] void reject_description(const std::filesystem::path& file, const std::string& key,
                                     const std::string& message) {
  throw std::runtime_error(file.string() + ": " + key + ": " + message);
}

// spec[key] as T, or `fallback` when absent and optional.
template <class T>
T spec_field(const std::filesystem::path& file, const json& spec, const std::string& key,
             std::optional<T> fallback = std::nullopt) {
  const auto it = spec.find(key);
  if (it == spec.end() || it->is_null()) {
    if (fallback) return *fallback;
    reject_description(file, "spec." + key, "missing");
  }
  try {
    return it->get<T>();
  } catch (const json::exception&) {
    reject_description(file, "spec." + key,
                       "has the wrong type (" + std::string(it->type_name()) + ")");
  }
}

}  // namespace

std::filesystem::path description_path(const std::filesystem::path& onnx) {
  auto path = onnx;
  path.replace_extension(".json");
  return path;
}

std::optional<ModelDescription> read_model_description(const std::filesystem::path& file) {
  std::error_code error;
  if (!std::filesystem::exists(file, error)) return std::nullopt;
  std::ifstream in(file);
  if (!in) reject_description(file, "file", "cannot be read");
  json document;
  try {
    document = json::parse(in);
  } catch (const json::parse_error& e) {
    reject_description(file, "file", std::string("is not JSON (") + e.what() + ")");
  }
  if (!document.is_object() || !document.contains("spec") || !document["spec"].is_object()) {
    reject_description(file, "spec", "missing (an object holding the network's input spec)");
  }
  const json& spec = document["spec"];
  ModelDescription model;
  model.path = file;
  auto& s = model.spec;
  s.input_width = spec_field<int>(file, spec, "input_width");
  s.input_height = spec_field<int>(file, spec, "input_height");
  const auto mean = spec_field<std::vector<double>>(file, spec, "mean_rgb");
  if (mean.size() != 3) reject_description(file, "spec.mean_rgb", "expected 3 numbers (R, G, B)");
  for (std::size_t i = 0; i < 3; ++i) s.mean_rgb[i] = mean[i];
  s.scale = spec_field<double>(file, spec, "scale");
  s.rgb = spec_field<bool>(file, spec, "rgb");
  s.classes = spec_field<std::vector<std::string>>(file, spec, "classes");
  s.soil_class = spec_field<int>(file, spec, "soil_class");
  s.crop_class = spec_field<int>(file, spec, "crop_class");
  s.weed_class = spec_field<int>(file, spec, "weed_class");
  s.ground_mm_per_px = spec_field<double>(file, spec, "ground_mm_per_px", 0.0);
  s.stride = spec_field<int>(file, spec, "stride", 32);
  s.input_channels = spec_field<int>(file, spec, "input_channels", 3);
  if (auto problem = vision::validate_dnn_spec(s)) reject_description(file, "spec", *problem);
  if (const auto licence = document.find("licence");
      licence != document.end() && licence->is_string()) {
    model.licence = licence->get<std::string>();
  }
  if (const auto training = document.find("training");
      training != document.end() && training->is_object()) {
    if (const auto mm = training->find("dataset_mm_per_px");
        mm != training->end() && mm->is_number() && mm->get<double>() > 0.0) {
      model.dataset_mm_per_px = mm->get<double>();
    }
  }
  return model;
}

}  // namespace weedspray::daemon
