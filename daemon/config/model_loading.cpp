// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/model_loading.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>

#include "daemon/config/config_loader.hpp"
#include "daemon/config/model_description.hpp"

#ifndef WEEDSPRAY_MODEL_DIR  // set by CMake: <datadir>/weedspray/models of the install prefix
#define WEEDSPRAY_MODEL_DIR "/usr/share/weedspray/models"
#endif

namespace weedspray::daemon {

vision::DnnModelSpec dnn_spec(const VisionSection& vision) {
  vision::DnnModelSpec spec;
  spec.input_width = vision.model_input_width;
  spec.input_height = vision.model_input_height;
  for (std::size_t i = 0; i < spec.mean_rgb.size() && i < vision.model_mean.size(); ++i) {
    spec.mean_rgb[i] = vision.model_mean[i];
  }
  spec.scale = vision.model_scale;
  spec.rgb = vision.model_rgb;
  spec.classes = vision.model_classes;
  spec.soil_class = vision.soil_class;
  spec.crop_class = vision.crop_class;
  spec.weed_class = vision.weed_class;
  return spec;
}

// The spec's own rules, each reported against the key that breaks it.
void check_model_spec(const Config& config) {
  const VisionSection& v = config.vision;
  if (v.model_mean.size() != 3) {
    throw VisionKeyError("vision.model_mean", "expected 3 numbers (R, G, B), got " +
                                                  std::to_string(v.model_mean.size()));
  }
  const int classes = static_cast<int>(v.model_classes.size());
  if (classes < 2) {
    throw VisionKeyError("vision.model_classes", "lists " + std::to_string(classes) +
                                                     " classes; a segmentation network has at "
                                                     "least 2");
  }
  const std::array<std::pair<const char*, int>, 3> ids = {{{"vision.soil_class", v.soil_class},
                                                           {"vision.crop_class", v.crop_class},
                                                           {"vision.weed_class", v.weed_class}}};
  for (const auto& [key, id] : ids) {
    if (id >= classes) {
      throw VisionKeyError(key, std::to_string(id) + " is not a class of model_classes (0.." +
                                    std::to_string(classes - 1) + ")");
    }
  }
  for (std::size_t i = 0; i < ids.size(); ++i) {
    for (std::size_t j = i + 1; j < ids.size(); ++j) {
      if (ids[i].second == ids[j].second) {
        // Name the one the files set (the other may be at its default).
        const bool j_set = config.sources.count(ids[j].first) > 0;
        const auto& [key, id] = j_set ? ids[j] : ids[i];
        const char* other = j_set ? ids[i].first : ids[j].first;
        throw VisionKeyError(key, "is class " + std::to_string(id) + ", which is already " + other);
      }
    }
  }
}

std::string spec_number_text(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

namespace {

std::string mean_text(const std::array<double, 3>& mean) {
  std::ostringstream out;
  out.precision(6);
  out << '[' << mean[0] << ", " << mean[1] << ", " << mean[2] << ']';
  return out.str();
}

std::string classes_text(const std::vector<std::string>& classes) {
  std::string text = "[";
  for (std::size_t i = 0; i < classes.size(); ++i) text += (i ? ", \"" : "\"") + classes[i] + "\"";
  return text + "]";
}

bool nearly_equal(double a, double b) {
  return std::abs(a - b) <= 1e-6 * std::max({1.0, std::abs(a), std::abs(b)});
}

// The model's own spec with the configuration's overrides: an input size set in a file
// squeezes the region to it (a multiple of the model's stride); every other key set in a file
// must agree with the JSON, since the network was trained to be fed one way only.
vision::DnnModelSpec merged_spec(const Config& config, const ModelDescription& model) {
  const VisionSection& v = config.vision;
  vision::DnnModelSpec spec = model.spec;
  const auto set = [&](const char* key) { return config.sources.count(key) > 0; };
  const auto refuse = [&](const char* key, const std::string& ours, const std::string& theirs) {
    throw VisionKeyError(key, "= " + ours + ", but the model's " + model.path.string() + " says " +
                                  theirs +
                                  "; remove the key (a model's JSON is its spec) or use a model "
                                  "trained that way");
  };
  for (const auto& [key, size, side] :
       {std::tuple{"vision.model_input_width", v.model_input_width, &spec.input_width},
        std::tuple{"vision.model_input_height", v.model_input_height, &spec.input_height}}) {
    if (!set(key)) continue;
    if (size % spec.stride != 0) {
      throw VisionKeyError(key, std::to_string(size) + " is not a multiple of " +
                                    std::to_string(spec.stride) + " (the network's stride, " +
                                    "spec.stride in " + model.path.string() + ")");
    }
    *side = size;
    spec.fixed_input = true;
  }
  std::array<double, 3> mean{};
  for (std::size_t i = 0; i < 3 && i < v.model_mean.size(); ++i) mean[i] = v.model_mean[i];
  if (set("vision.model_mean") &&
      !(nearly_equal(mean[0], spec.mean_rgb[0]) && nearly_equal(mean[1], spec.mean_rgb[1]) &&
        nearly_equal(mean[2], spec.mean_rgb[2]))) {
    refuse("vision.model_mean", mean_text(mean), "spec.mean_rgb = " + mean_text(spec.mean_rgb));
  }
  if (set("vision.model_scale") && !nearly_equal(v.model_scale, spec.scale)) {
    refuse("vision.model_scale", spec_number_text(v.model_scale),
           "spec.scale = " + spec_number_text(spec.scale));
  }
  if (set("vision.model_rgb") && v.model_rgb != spec.rgb) {
    refuse("vision.model_rgb", v.model_rgb ? "true" : "false",
           spec.rgb ? "spec.rgb = true (R, G, B order)" : "spec.rgb = false (B, G, R order)");
  }
  if (set("vision.model_classes") && v.model_classes != spec.classes) {
    refuse(
        "vision.model_classes",
        classes_text(v.model_classes) + " (" + std::to_string(v.model_classes.size()) + " classes)",
        "spec.classes = " + classes_text(spec.classes) + " (" +
            std::to_string(spec.classes.size()) + " classes)");
  }
  for (const auto& [key, ours, theirs, name] :
       {std::tuple{"vision.soil_class", v.soil_class, spec.soil_class, "spec.soil_class"},
        std::tuple{"vision.crop_class", v.crop_class, spec.crop_class, "spec.crop_class"},
        std::tuple{"vision.weed_class", v.weed_class, spec.weed_class, "spec.weed_class"}}) {
    if (set(key) && ours != theirs) {
      refuse(key, std::to_string(ours), std::string(name) + " = " + std::to_string(theirs));
    }
  }
  return spec;
}

std::filesystem::path find_model(const Config& config) {
  const std::filesystem::path wanted(config.vision.model);
  if (wanted.empty()) throw VisionKeyError("vision.model", "is empty; dnn and hybrid need a model");
  std::error_code error;
  if (wanted.is_absolute()) {
    if (!std::filesystem::exists(wanted, error)) {
      throw VisionKeyError("vision.model", config.vision.model + " does not exist");
    }
    return wanted;
  }
  const auto source = config.sources.find("vision.model");
  const std::string set_in = source == config.sources.end() ? "" : source->second.file;
  std::string tried;
  for (const auto& dir : model_search_dirs(set_in)) {
    const auto candidate = dir / wanted;
    if (std::filesystem::exists(candidate, error)) return candidate;
    tried += (tried.empty() ? "" : ", ") + candidate.string();
  }
  throw VisionKeyError("vision.model",
                       config.vision.model + " not found (looked for " + tried + ")");
}

}  // namespace

std::shared_ptr<LoadedModel> read_model(const Config& config) {
  auto model = std::make_shared<LoadedModel>();
  model->path = find_model(config);
  std::error_code error;
  if (!std::filesystem::is_regular_file(model->path, error)) {
    throw VisionKeyError("vision.model", model->path.string() + " is not a regular file");
  }
  // Far above any network a sprayer's board runs in a frame's time (the shipped one is ~2 MB).
  constexpr std::uintmax_t kMaxModelBytes = 256u << 20;
  if (std::filesystem::file_size(model->path, error) > kMaxModelBytes) {
    throw VisionKeyError("vision.model", model->path.string() + " is larger than 256 MiB");
  }
  std::ifstream in(model->path, std::ios::binary);
  if (!in) throw VisionKeyError("vision.model", model->path.string() + " cannot be read");
  model->onnx.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) throw VisionKeyError("vision.model", model->path.string() + " cannot be read");
  if (model->onnx.empty()) throw VisionKeyError("vision.model", model->path.string() + " is empty");
  model->description_path = description_path(model->path);
  std::optional<ModelDescription> description;
  try {
    description = read_model_description(model->description_path);
  } catch (const std::runtime_error& error) {
    throw VisionKeyError("vision.model", error.what());
  }
  if (!description) {
    throw VisionKeyError("vision.model",
                         model->path.string() + " has no description beside it (" +
                             model->description_path.string() +
                             ": the spec the network is fed by, its classes and the ground "
                             "scale it learnt at; tools/train/train.py writes it)");
  }
  model->spec = merged_spec(config, *description);
  model->licence = description->licence;
  model->dataset_mm_per_px = description->dataset_mm_per_px;
  return model;
}

std::vector<std::filesystem::path> model_search_dirs(const std::string& set_in_file) {
  std::vector<std::filesystem::path> dirs;
  if (!set_in_file.empty()) {
    const auto dir = std::filesystem::path(set_in_file).parent_path();
    dirs.push_back(dir.empty() ? std::filesystem::path(".") : dir);
  }
  dirs.emplace_back(WEEDSPRAY_MODEL_DIR);
#ifdef WEEDSPRAY_SOURCE_MODEL_DIR
  dirs.emplace_back(WEEDSPRAY_SOURCE_MODEL_DIR);
#endif
  return dirs;
}

}  // namespace weedspray::daemon
