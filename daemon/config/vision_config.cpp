// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/vision_config.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>
#include <sstream>
#include <tuple>

#include "daemon/config/model_loading.hpp"
#include "vision/threshold.hpp"
#include "vision/vegetation_index.hpp"
#include "vision/weed_source.hpp"

namespace weedspray::daemon {
namespace {

std::string centimetres(double metres) {
  std::ostringstream out;
  out.precision(3);
  out << metres * 100.0 << " cm";
  return out.str();
}

// What the camera sees across its frame, from its ground scale.
double camera_view_width_m(const CameraSection& camera) {
  return camera_ground_mm_per_px(camera) * camera.width / 1000.0;
}

vision::PipelineConfig pipeline_config_with(const Config& config, const CameraSection& camera,
                                            const vision::DnnModelSpec& spec);

// The pixels of a camera's frame the pipeline looks at (its region of interest).
std::pair<int, int> region_size(const CameraSection& camera) {
  const vision::RegionOfInterest roi = vision::default_pipeline_config().roi;
  return {static_cast<int>(std::lround((roi.right - roi.left) * camera.width)),
          static_cast<int>(std::lround((roi.bottom - roi.top) * camera.height))};
}

// How a camera's view meets the model's ground scale: a GREY camera cannot feed a colour
// network, a camera much coarser than the model hides the weeds it learnt, and a view that
// needs a larger input than vision.max_network_pixels costs more than a frame's time.
void check_camera_against_model(const Config& config, std::size_t i,
                                const vision::DnnModelSpec& spec, const std::string& model) {
  const CameraSection& camera = config.cameras[i];
  const std::string which = "camera[" + std::to_string(i) + "]";
  if (camera.format == "GREY") {
    throw VisionKeyError(which + ".format",
                         "GREY gives one channel, but " + model + " takes " +
                             std::to_string(spec.input_channels) +
                             " colour channels: use YUYV, MJPG or RGB3, or a weed source without "
                             "a model (vegetation with index = \"mono\")");
  }
  if (spec.fixed_input || !(spec.ground_mm_per_px > 0.0)) return;
  const double frame_mm = camera_ground_mm_per_px(camera);
  const auto [region_w, region_h] = region_size(camera);
  const vision::NetworkInputSize input =
      vision::network_input_size(spec, frame_mm, region_w, region_h);
  const std::string geometry = config.sources.count(which + ".ground_mm_per_px")
                                   ? which + ".ground_mm_per_px"
                                   : which + ".mount_height_m";
  // Upsampling adds no detail: past twice the model's scale, plants are smaller than any it
  // learnt from (its zoom augmentation spans well under 2x).
  constexpr double kMaxCoarser = 2.0;
  if (input.scale > kMaxCoarser) {
    throw VisionKeyError(geometry, which + " sees " + spec_number_text(frame_mm) +
                                       " mm per pixel on the ground, " +
                                       spec_number_text(input.scale) + "x coarser than the " +
                                       spec_number_text(spec.ground_mm_per_px) + " mm/px " + model +
                                       " learnt at (more than 2x): mount it lower, narrow its "
                                       "view, or train for this scale (tools/train/train.py "
                                       "--target-mm-per-px " +
                                       spec_number_text(frame_mm) + ")");
  }
  if (input.pixels() > config.vision.max_network_pixels) {
    throw VisionKeyError(geometry,
                         which + "'s " + std::to_string(region_w) + "x" + std::to_string(region_h) +
                             " px at " + spec_number_text(frame_mm) + " mm/px needs a " +
                             std::to_string(input.width) + "x" + std::to_string(input.height) +
                             " network input to match "
                             "the " +
                             spec_number_text(spec.ground_mm_per_px) + " mm/px " + model +
                             " learnt at, more than "
                             "vision.max_network_pixels (" +
                             std::to_string(config.vision.max_network_pixels) +
                             "): raise that if the board keeps up (weedspray-lab "
                             "bench-vision), use a model trained coarser "
                             "(--target-mm-per-px), or a smaller frame");
  }
}

}  // namespace

double camera_ground_mm_per_px(const CameraSection& camera) {
  if (camera.ground_mm_per_px > 0.0) return camera.ground_mm_per_px;
  // The optical axis meets the ground at range h / cos(tilt); one pixel subtends vfov / height
  // (square pixels), so across travel it covers range x that angle.
  const double range_m =
      camera.mount_height_m / std::cos(camera.tilt_deg * std::numbers::pi / 180.0);
  const double pixel_rad = camera.vfov_deg * std::numbers::pi / 180.0 / camera.height;
  return range_m * pixel_rad * 1000.0;
}

vision::PipelineConfig pipeline_config(const Config& config, const CameraSection& camera,
                                       const LoadedModel* model) {
  if (!model) model = config.model.get();
  return pipeline_config_with(config, camera, model ? model->spec : dnn_spec(config.vision));
}

namespace {

vision::PipelineConfig pipeline_config_with(const Config& config, const CameraSection& camera,
                                            const vision::DnnModelSpec& spec) {
  const VisionSection& v = config.vision;
  vision::PipelineConfig c = vision::default_pipeline_config();
  // "default" keeps the library's measured choice; other names are validated by the config.
  if (auto index = vision::parse_vegetation_index(v.index)) c.index = *index;
  if (auto method = vision::parse_threshold_method(v.threshold)) c.threshold = *method;
  if (v.fixed_threshold >= 0) c.threshold_params.fixed_threshold = v.fixed_threshold;
  c.rows = v.grid_rows;
  c.cols = camera.nozzle_count;
  c.weed_source = vision::parse_weed_source(v.weed_source).value_or(c.weed_source);
  c.inter_row_rule.row_band_fraction = v.row_band_cm / 100.0 / camera_view_width_m(camera);
  c.dnn = spec;
  c.frame_mm_per_px = camera_ground_mm_per_px(camera);
  c.crop_margin_px = static_cast<int>(std::lround(v.crop_margin_cm * 10.0 / c.frame_mm_per_px));
  c.min_plant_px = vision::area_in_pixels(v.min_plant_cm2, c.frame_mm_per_px);
  return c;
}

}  // namespace

std::vector<std::string> describe_model_use(const Config& config) {
  std::vector<std::string> lines;
  if (!config.model) return lines;
  const vision::DnnModelSpec& spec = config.model->spec;
  for (std::size_t i = 0; i < config.cameras.size(); ++i) {
    const vision::PipelineConfig pipeline = pipeline_config(config, config.cameras[i]);
    const auto [region_w, region_h] = region_size(config.cameras[i]);
    const vision::NetworkInputSize input =
        vision::network_input_size(spec, pipeline.frame_mm_per_px, region_w, region_h);
    std::ostringstream line;
    line.precision(3);
    line << "camera[" << i << "]: " << pipeline.frame_mm_per_px << " mm/px -> "
         << config.model->path.filename().string() << " (";
    if (spec.ground_mm_per_px > 0.0) {
      line << "learnt at " << spec.ground_mm_per_px << " mm/px";
    } else {
      line << "ground scale not stated";
    }
    if (!config.model->licence.empty()) line << "; " << config.model->licence;
    line << "): network input " << input.width << "x" << input.height
         << (spec.fixed_input || !(spec.ground_mm_per_px > 0.0) ? " (squeezed)" : "");
    lines.push_back(line.str());
  }
  return lines;
}

std::shared_ptr<const LoadedModel> check_weed_source(const Config& config) {
  const auto source = vision::parse_weed_source(config.vision.weed_source);
  if (!source) {
    throw VisionKeyError("vision.weed_source", "\"" + config.vision.weed_source +
                                                   "\" is not a weed source of the vision library");
  }
  std::shared_ptr<LoadedModel> model;
  if (vision::needs_model(*source)) {
    check_model_spec(config);
    model = read_model(config);
  }
  const vision::DnnModelSpec spec = model ? model->spec : dnn_spec(config.vision);
  for (std::size_t i = 0; i < config.cameras.size(); ++i) {
    const auto& camera = config.cameras[i];
    const std::string which = "camera[" + std::to_string(i) + "]";
    const double view_m = camera_view_width_m(camera);
    if (*source == vision::WeedSource::kInterRow && config.vision.row_band_cm / 100.0 >= view_m) {
      throw VisionKeyError("vision.row_band_cm",
                           "is as wide as " + which + "'s view (" + centimetres(view_m) +
                               " across at " + spec_number_text(camera_ground_mm_per_px(camera)) +
                               " mm/px)");
    }
    if (model) check_camera_against_model(config, i, spec, model->path.filename().string());
    try {
      vision::validate(pipeline_config_with(config, camera, spec));
    } catch (const std::invalid_argument& error) {
      const std::string key = *source == vision::WeedSource::kHybrid   ? "vision.crop_margin_cm"
                              : *source == vision::WeedSource::kPlants ? "vision.min_plant_cm2"
                                                                       : "vision.weed_source";
      throw VisionKeyError(key, which + ": " + error.what());
    }
  }
  if (!model) return nullptr;
  try {
    // Loads the network and runs it once: an unloadable file or an output that is not one
    // score map per class fails here, at load, not in the field.
    const vision::Pipeline probe(pipeline_config_with(config, config.cameras.front(), spec),
                                 model->onnx);
  } catch (const std::invalid_argument& error) {
    std::string what = error.what();
    while (!what.empty() && std::isspace(static_cast<unsigned char>(what.back()))) what.pop_back();
    // The vision library reports a wrong number of output channels as the output's shape.
    const bool shape = what.find("output shape") != std::string::npos;
    throw VisionKeyError(shape && config.sources.count("vision.model_classes")
                             ? "vision.model_classes"
                             : "vision.model",
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
