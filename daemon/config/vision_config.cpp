#include "daemon/config/vision_config.hpp"

#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>

#include "vision/threshold.hpp"
#include "vision/vegetation_index.hpp"
#include "vision/weed_source.hpp"

#ifndef WEEDSPRAY_MODEL_DIR  // set by CMake: <datadir>/weedspray/models of the install prefix
#define WEEDSPRAY_MODEL_DIR "/usr/share/weedspray/models"
#endif

namespace weedspray::daemon {
namespace {

std::string centimetres(double metres) {
  std::ostringstream out;
  out.precision(3);
  out << metres * 100.0 << " cm";
  return out.str();
}

double camera_ground_width_m(const Config& config, const CameraSection& camera) {
  return camera.nozzle_count * config.boom.nozzle_width_m;
}

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
  for (const auto& [key, size] : {std::pair{"vision.model_input_width", v.model_input_width},
                                  std::pair{"vision.model_input_height", v.model_input_height}}) {
    if (size % 32 != 0) {
      throw VisionKeyError(key, std::to_string(size) +
                                    " is not a multiple of 32 (the network halves its input "
                                    "5 times)");
    }
  }
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
  if (auto problem = vision::validate_dnn_spec(dnn_spec(v))) {
    throw VisionKeyError("vision.model", *problem);
  }
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
  return model;
}

}  // namespace

double ground_m_per_px(const Config& config, const CameraSection& camera) {
  return camera_ground_width_m(config, camera) / camera.width;
}

vision::PipelineConfig pipeline_config(const Config& config, const CameraSection& camera) {
  const VisionSection& v = config.vision;
  vision::PipelineConfig c = vision::default_pipeline_config();
  // "default" keeps the library's measured choice; other names are validated by the config.
  if (auto index = vision::parse_vegetation_index(v.index)) c.index = *index;
  if (auto method = vision::parse_threshold_method(v.threshold)) c.threshold = *method;
  if (v.fixed_threshold >= 0) c.threshold_params.fixed_threshold = v.fixed_threshold;
  c.rows = v.grid_rows;
  c.cols = camera.nozzle_count;
  c.weed_source = vision::parse_weed_source(v.weed_source).value_or(c.weed_source);
  c.inter_row_rule.row_band_fraction =
      v.row_band_cm / 100.0 / camera_ground_width_m(config, camera);
  c.dnn = dnn_spec(v);
  c.crop_margin_px =
      static_cast<int>(std::lround(v.crop_margin_cm / 100.0 / ground_m_per_px(config, camera)));
  return c;
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

std::shared_ptr<const LoadedModel> check_weed_source(const Config& config) {
  const auto source = vision::parse_weed_source(config.vision.weed_source);
  if (!source) {
    throw VisionKeyError("vision.weed_source", "\"" + config.vision.weed_source +
                                                   "\" is not a weed source of the vision library");
  }
  if (vision::needs_model(*source)) check_model_spec(config);
  for (std::size_t i = 0; i < config.cameras.size(); ++i) {
    const auto& camera = config.cameras[i];
    const std::string which = "camera[" + std::to_string(i) + "]";
    const double view_m = camera_ground_width_m(config, camera);
    if (*source == vision::WeedSource::kInterRow && config.vision.row_band_cm / 100.0 >= view_m) {
      throw VisionKeyError("vision.row_band_cm", "is as wide as " + which + "'s view (" +
                                                     centimetres(view_m) +
                                                     ": nozzle_count x boom.nozzle_width_m)");
    }
    try {
      vision::validate(pipeline_config(config, camera));
    } catch (const std::invalid_argument& error) {
      const std::string key =
          *source == vision::WeedSource::kHybrid ? "vision.crop_margin_cm" : "vision.weed_source";
      throw VisionKeyError(key, which + ": " + error.what());
    }
  }
  if (!vision::needs_model(*source)) return nullptr;
  auto model = read_model(config);
  try {
    // Loads the network and runs it once: an unloadable file or an output that is not one
    // score map per class of model_classes fails here, at load, not in the field.
    const vision::Pipeline probe(pipeline_config(config, config.cameras.front()), model->onnx);
  } catch (const std::invalid_argument& error) {
    std::string what = error.what();
    while (!what.empty() && std::isspace(static_cast<unsigned char>(what.back()))) what.pop_back();
    // The vision library reports a wrong number of output channels as the output's shape.
    const bool shape = what.find("output shape") != std::string::npos;
    throw VisionKeyError(shape ? "vision.model_classes" : "vision.model",
                         model->path.string() + ": " + what);
  }
  return model;
}

}  // namespace weedspray::daemon

// The full load: the files, then the weed source (config_loader.hpp says why they are apart).
namespace weedspray::daemon {

Config load_config(const std::filesystem::path& main_file) {
  return load_config_files(main_file, &check_weed_source);
}

Config load_config_from_strings(const std::vector<std::pair<std::string, std::string>>& documents) {
  return load_config_documents(documents, &check_weed_source);
}

}  // namespace weedspray::daemon
