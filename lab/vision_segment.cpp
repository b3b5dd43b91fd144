// SPDX-License-Identifier: Apache-2.0
// segment: threshold, zone weed (and crop) densities and density levels of field images, with
// an optional overlay PNG showing crop and weed, the zone grid and each zone's weed density.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "lab/vision_dataset.hpp"
#include "lab/vision_tools.hpp"
#include "lab/weed_eval.hpp"
#include "lab/weed_eval_command.hpp"
#include "lab/weed_model.hpp"
#include "vision/overlay.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::lab {
namespace {

struct SegmentOptions {
  std::vector<std::string> images;
  std::string index;
  std::string threshold;
  std::string grid = "1x4";
  std::string overlay;
  std::string weed_source = "vegetation";
  std::string model;
  int crop_margin_px = kDefaultCropMarginPx;
  bool json = false;
};

std::string join_names(std::span<const std::string_view> names) {
  std::string joined;
  for (std::string_view name : names) joined += (joined.empty() ? "" : ", ") + std::string(name);
  return joined;
}

vision::PipelineConfig config_from(const SegmentOptions& options, WeedModel& model) {
  vision::PipelineConfig config = vision::default_pipeline_config();
  config.weed_source = parse_weed_source_option("--weed-source", options.weed_source);
  config.crop_margin_px = options.crop_margin_px;
  if (!options.model.empty()) {
    model = read_weed_model(options.model);
    config.dnn = model.spec;
  } else if (vision::needs_model(config.weed_source)) {
    throw std::runtime_error("--weed-source " + options.weed_source + " needs --model FILE");
  }
  if (!options.index.empty()) {
    const auto index = vision::parse_vegetation_index(options.index);
    if (!index) {
      throw std::runtime_error("--index " + options.index + ": unknown (one of " +
                               join_names(vision::vegetation_index_names()) + ")");
    }
    config.index = *index;
  }
  if (!options.threshold.empty()) {
    const auto method = vision::parse_threshold_method(options.threshold);
    if (!method) {
      throw std::runtime_error("--threshold " + options.threshold + ": unknown (one of " +
                               join_names(vision::threshold_method_names()) + ")");
    }
    config.threshold = *method;
  }
  parse_grid_option("--grid", options.grid, config.rows, config.cols);
  config.inter_row_map = true;
  try {
    vision::validate(config);
  } catch (const std::invalid_argument& error) {
    throw std::runtime_error("--grid " + options.grid + ": " + error.what());
  }
  return config;
}

// OUT.png for one image; OUT_<stem>.png for each of several.
std::filesystem::path overlay_path(const std::string& out, const std::filesystem::path& image,
                                   bool several) {
  if (!several) return out;
  std::filesystem::path path = out;
  const std::string extension = path.has_extension() ? path.extension().string() : ".png";
  path.replace_filename(path.stem().string() + "_" + image.stem().string() + extension);
  return path;
}

void write_overlay(const cv::Mat& bgr, vision::Pipeline& pipeline,
                   const vision::FrameResult& result, const std::filesystem::path& path) {
  const vision::ImageView frame{bgr.data, bgr.cols, bgr.rows, bgr.step[0],
                                vision::PixelFormat::kBgr24};
  const vision::OverlayZones zones{result.rows, result.cols, result.densities(), {}};
  vision::BgrImage overlay =
      vision::draw_overlay(frame, pipeline.class_map(), pipeline.region(), zones);
  if (!cv::imwrite(path.string(),
                   cv::Mat(overlay.height, overlay.width, CV_8UC3, overlay.pixels.data()))) {
    throw std::runtime_error(path.string() + ": cannot write overlay");
  }
}

int run_segment(const SegmentOptions& options) {
  WeedModel model;
  const vision::PipelineConfig config = config_from(options, model);
  vision::Pipeline pipeline(config, model.onnx);
  const bool several = options.images.size() > 1;
  if (options.json) std::printf("{\"images\": [");
  for (std::size_t i = 0; i < options.images.size(); ++i) {
    const std::filesystem::path path = options.images[i];
    const cv::Mat bgr = read_bgr_image(path);
    const vision::FrameResult& result =
        pipeline.process({bgr.data, bgr.cols, bgr.rows, bgr.step[0], vision::PixelFormat::kBgr24});
    if (!pipeline.last_frame_ok()) {
      throw std::runtime_error(path.string() + ": " +
                               (pipeline.last_error().empty()
                                    ? "image too small for a " + options.grid + " grid"
                                    : pipeline.last_error()));
    }
    std::string overlay;
    if (!options.overlay.empty()) {
      overlay = overlay_path(options.overlay, path, several).string();
      write_overlay(bgr, pipeline, result, overlay);
    }
    if (options.json) {
      std::printf(
          "%s{\"file\": \"%s\", \"weed_source\": \"%s\", \"index\": \"%s\", "
          "\"threshold_method\": \"%s\", "
          "\"threshold\": %d, \"bimodal\": %s, \"vegetation_fraction\": %.5f, "
          "\"rows\": %d, \"cols\": %d, \"zones\": [",
          i == 0 ? "" : ", ", path.string().c_str(),
          std::string(to_string(config.weed_source)).c_str(),
          std::string(to_string(config.index)).c_str(),
          std::string(to_string(config.threshold)).c_str(), result.threshold,
          result.bimodal ? "true" : "false", result.vegetation_fraction, result.rows, result.cols);
      for (int zone = 0; zone < result.rows * result.cols; ++zone) {
        std::printf(
            "%s{\"row\": %d, \"col\": %d, \"density\": %.5f, \"crop_density\": %.5f, "
            "\"level\": \"%s\"}",
            zone == 0 ? "" : ", ", zone / result.cols, zone % result.cols,
            result.zone_density[zone], result.crop_density[zone],
            std::string(to_string(result.zone_level[zone])).c_str());
      }
      std::printf("], \"inter_row\": [");
      const auto intervals = result.inter_row.view();
      for (std::size_t k = 0; k < intervals.size(); ++k) {
        std::printf(
            "%s{\"first_column\": %d, \"last_column\": %d, \"share\": %.5f, "
            "\"level\": \"%s\"}",
            k == 0 ? "" : ", ", intervals[k].first_column, intervals[k].last_column,
            intervals[k].share, std::string(to_string(intervals[k].level)).c_str());
      }
      std::printf("]%s%s%s}", overlay.empty() ? "" : ", \"overlay\": \"", overlay.c_str(),
                  overlay.empty() ? "" : "\"");
      continue;
    }
    std::printf("%s: weed source %s, index %s, threshold %s = %d (%s), vegetation %.2f%%\n",
                path.string().c_str(), std::string(to_string(config.weed_source)).c_str(),
                std::string(to_string(config.index)).c_str(),
                std::string(to_string(config.threshold)).c_str(), result.threshold,
                result.bimodal ? "bimodal" : "not bimodal: fixed level",
                100.0 * result.vegetation_fraction);
    for (int row = 0; row < result.rows; ++row) {
      std::printf("  row %d:", row);
      for (int col = 0; col < result.cols; ++col) {
        const int zone = row * result.cols + col;
        std::printf("  %6.2f%% %-11s", 100.0 * result.zone_density[zone],
                    std::string(to_string(result.zone_level[zone])).c_str());
        if (config.weed_source != vision::WeedSource::kVegetation) {
          std::printf("(crop %5.2f%%)", 100.0 * result.crop_density[zone]);
        }
      }
      std::printf("\n");
    }
    std::printf("  inter-row intervals (columns <= %.2f of the max):", config.inter_row_fraction);
    for (const vision::InterRowInterval& interval : result.inter_row.view()) {
      std::printf(" [%d-%d] p=%.4f %s;", interval.first_column, interval.last_column,
                  interval.share, std::string(to_string(interval.level)).c_str());
    }
    std::printf("\n");
    if (!overlay.empty()) std::printf("  overlay: %s\n", overlay.c_str());
  }
  if (options.json) std::printf("]}\n");
  return 0;
}

}  // namespace

void add_segment_command(CLI::App& app) {
  auto options = std::make_shared<SegmentOptions>();
  CLI::App* segment = app.add_subcommand(
      "segment", "Threshold, zone densities and levels of field images (optional overlay PNG)");
  segment->add_option("images", options->images, "Field images")
      ->required()
      ->check(CLI::ExistingFile);
  segment->add_option("--index", options->index,
                      "Vegetation index: " + join_names(vision::vegetation_index_names()) +
                          " (default: the pipeline default)");
  segment->add_option("--threshold", options->threshold,
                      "Threshold method: " + join_names(vision::threshold_method_names()) +
                          " (default: the pipeline default)");
  segment->add_option("--grid", options->grid, "Zone grid ROWSxCOLS")->capture_default_str();
  segment->add_option("--overlay", options->overlay,
                      "Write crop (blue), weed (red), the grid and weed densities to this PNG "
                      "(OUT_<stem>.png for several images)");
  segment
      ->add_option("--weed-source", options->weed_source,
                   "What counts as weed: " + weed_source_list())
      ->capture_default_str();
  segment
      ->add_option("--model", options->model,
                   "ONNX weed model for the sources that need one (spec from FILE.json)")
      ->check(CLI::ExistingFile);
  segment->add_option("--crop-margin-px", options->crop_margin_px, "hybrid: crop margin in pixels")
      ->capture_default_str();
  segment->add_flag("--json", options->json, "Print one JSON object");
  segment->callback([options] {
    try {
      run_segment(*options);
    } catch (const std::exception& error) {
      std::cerr << "weedspray-lab segment: " << error.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace weedspray::lab
