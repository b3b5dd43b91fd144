// SPDX-License-Identifier: Apache-2.0
#include "lab/weed_eval_command.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

#include "daemon/config/config.hpp"
#include "lab/weed_eval.hpp"
#include "lab/weed_model.hpp"

namespace weedspray::lab {
namespace {

struct Setup {
  vision::PipelineConfig base = vision::default_pipeline_config();
  std::vector<std::uint8_t> onnx;
  std::vector<vision::WeedSource> sources;
  ZoneRule zones;
  double dataset_mm_per_px = 0;
  double image_mm_per_px = 0;  // the images' own ground scale; 0 = unknown
};

Setup setup_from(const WeedEvalOptions& options) {
  Setup setup;
  setup.zones.decision_threshold = default_decision_threshold();
  double crop_margin_cm = daemon::default_config().vision.crop_margin_cm;
  double min_plant_cm2 = daemon::default_config().vision.min_plant_cm2;
  if (!options.config.empty()) {
    DaemonVisionSetup daemon = read_daemon_vision_setup(options.config);
    setup.base = daemon.pipeline;
    setup.onnx = std::move(daemon.onnx);
    setup.zones.decision_threshold = daemon.decision_threshold;
    setup.zones.rows = setup.base.rows;
    setup.zones.cols = setup.base.cols;
    setup.dataset_mm_per_px = daemon.dataset_mm_per_px;
    crop_margin_cm = daemon.crop_margin_cm;
    min_plant_cm2 = daemon.min_plant_cm2;
  }
  if (!options.model.empty()) {
    WeedModel model = read_weed_model(options.model);
    setup.base.dnn = model.spec;
    setup.onnx = std::move(model.onnx);
    setup.dataset_mm_per_px = model.dataset_mm_per_px;
  }
  if (options.image_mm_per_px < 0) throw std::runtime_error("--image-mm-per-px must be >= 0");
  // The images are photos, not the configured camera's frames: their own scale, unless they
  // are resampled to a camera's.
  setup.image_mm_per_px =
      options.image_mm_per_px > 0 ? options.image_mm_per_px : setup.dataset_mm_per_px;
  if (options.frame_mm_per_px < 0) throw std::runtime_error("--frame-mm-per-px must be >= 0");
  if (options.frame_mm_per_px > 0 && !(setup.image_mm_per_px > 0)) {
    throw std::runtime_error(
        "--frame-mm-per-px needs the images' own scale: give --image-mm-per-px (or a --model "
        "whose JSON states training.dataset_mm_per_px)");
  }
  setup.base.frame_mm_per_px =
      options.frame_mm_per_px > 0 ? options.frame_mm_per_px : setup.image_mm_per_px;
  setup.base.crop_margin_px =
      crop_margin_px_at(crop_margin_cm, setup.base.frame_mm_per_px, kDefaultCropMarginPx);
  setup.base.min_plant_px =
      vision::area_in_pixels(min_plant_cm2, setup.base.frame_mm_per_px, kDefaultMinPlantPx);
  if (!options.grid.empty()) {
    parse_grid_option("--grid", options.grid, setup.zones.rows, setup.zones.cols);
  }
  if (options.decision_threshold >= 0) setup.zones.decision_threshold = options.decision_threshold;
  if (!(options.weedy_share > 0 && options.weedy_share <= 1)) {
    throw std::runtime_error("--weedy-share must lie in (0, 1]");
  }
  setup.zones.weedy_share = options.weedy_share;
  if (options.crop_margin_px >= 0) setup.base.crop_margin_px = options.crop_margin_px;
  if (options.min_plant_px >= 1) setup.base.min_plant_px = options.min_plant_px;
  if (options.row_band_fraction >= 0) {
    setup.base.inter_row_rule.row_band_fraction = options.row_band_fraction;
  }

  if (!options.weed_source.empty()) {
    setup.sources = {parse_weed_source_option("--weed-source", options.weed_source)};
  } else if (!options.config.empty() && options.model.empty()) {
    setup.sources = {setup.base.weed_source};
  } else {
    setup.sources = {vision::WeedSource::kVegetation, vision::WeedSource::kInterRow};
    if (!setup.onnx.empty()) {
      setup.sources.push_back(vision::WeedSource::kDnn);
      setup.sources.push_back(vision::WeedSource::kHybrid);
      setup.sources.push_back(vision::WeedSource::kPlants);
      setup.sources.push_back(vision::WeedSource::kDnnVegetation);
    }
  }
  for (const vision::WeedSource source : setup.sources) {
    if (vision::needs_model(source) && setup.onnx.empty()) {
      throw std::runtime_error("weed source " + std::string(to_string(source)) +
                               " needs a model: give --model FILE (or a --config whose "
                               "vision.weed_source loads one)");
    }
  }
  return setup;
}

void print_interval(const char* name, const std::array<double, 2>& interval, bool last = false) {
  std::printf("\"%s\": [%.4f, %.4f]%s", name, interval[0], interval[1], last ? "" : ", ");
}

void print_intervals(const WeedEvalRow& row) {
  const ImageIntervals ci = image_intervals(row);
  std::printf("\"intervals\": {\"level\": 0.95, ");
  print_interval("miou", ci.miou);
  print_interval("crop_iou", ci.crop_iou);
  print_interval("weed_iou", ci.weed_iou);
  print_interval("recall", ci.recall);
  print_interval("crop_only_left_dry", ci.crop_only_left_dry);
  print_interval("bare_left_dry", ci.bare_left_dry, true);
  std::printf("}, ");
}

void print_json(std::size_t images, const std::vector<WeedEvalRow>& rows, const ZoneRule& zones,
                bool class_masks) {
  std::printf("{\"images\": %zu, \"pipelines\": [", images);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const WeedEvalRow& row = rows[i];
    std::printf("%s{\"weed_source\": \"%s\", ", i == 0 ? "" : ", ",
                std::string(to_string(row.source)).c_str());
    if (class_masks) {
      std::printf(
          "\"iou\": {\"soil\": %.4f, \"crop\": %.4f, \"weed\": %.4f}, \"miou\": %.4f, "
          "\"mpa\": %.4f, \"zones\": {\"grid\": \"%dx%d\", \"weedy\": %d, \"recall\": %.4f, "
          "\"clean_left_dry\": %.4f, \"crop_only\": %d, \"crop_only_left_dry\": %.4f, "
          "\"bare\": %d, \"bare_left_dry\": %.4f}, ",
          row.scores.iou[0], row.scores.iou[1], row.scores.iou[2], row.scores.miou, row.scores.mpa,
          zones.rows, zones.cols, row.zones.weedy, row.zones.recall(), row.zones.clean_left_dry(),
          row.zones.crop_only, row.zones.crop_only_left_dry(), row.zones.bare,
          row.zones.bare_left_dry());
      print_intervals(row);
    } else {
      std::printf("\"vegetation_iou\": %.4f, ", row.vegetation_iou);
    }
    std::printf("\"ms_per_image\": %.3f}", row.ms_per_image);
  }
  std::printf("]}\n");
}

void print_table(const WeedEvalOptions& options, std::size_t images,
                 const std::vector<WeedEvalRow>& rows, const Setup& setup) {
  const ZoneRule& zones = setup.zones;
  std::printf("%zu images from %s%s%s\n", images, options.images_dir.c_str(),
              options.list.empty() ? "" : ", list ", options.list.c_str());
  if (options.frame_mm_per_px > 0) {
    std::printf("resampled from %.3g to %.4g mm/px, as a camera at that scale sees them\n",
                setup.image_mm_per_px, options.frame_mm_per_px);
  }
  if (options.class_masks) {
    std::printf(
        "zones %dx%d: weedy when >= %.2f %% of the zone is weed; sprayed when the weed density "
        ">= %.4f (decision threshold); hybrid margin %d px; least plant %d px; one thread\n\n",
        zones.rows, zones.cols, 100.0 * zones.weedy_share, zones.decision_threshold,
        setup.base.crop_margin_px, setup.base.min_plant_px);
    std::printf("%-11s %7s %7s %7s %7s %7s %8s %6s %7s %10s %9s %9s %9s\n", "weed_source",
                "IoU_soil", "crop", "weed", "MIoU", "MPA", "veg_IoU", "weedy", "recall",
                "clean_dry", "crop_dry", "bare_dry", "ms/image");
    for (const WeedEvalRow& row : rows) {
      std::printf("%-11s %7.4f %7.4f %7.4f %7.4f %7.4f %8.4f %6d %7.4f %10.4f %9.4f %9.4f %9.2f\n",
                  std::string(to_string(row.source)).c_str(), row.scores.iou[0], row.scores.iou[1],
                  row.scores.iou[2], row.scores.miou, row.scores.mpa, row.vegetation_iou,
                  row.zones.weedy, row.zones.recall(), row.zones.clean_left_dry(),
                  row.zones.crop_only_left_dry(), row.zones.bare_left_dry(), row.ms_per_image);
    }
    std::printf("\n95 %% intervals over images (bootstrap): MIoU, weed IoU, recall, crop_dry\n");
    for (const WeedEvalRow& row : rows) {
      const ImageIntervals ci = image_intervals(row);
      std::printf("%-11s %.3f-%.3f  %.3f-%.3f  %.3f-%.3f  %.3f-%.3f\n",
                  std::string(to_string(row.source)).c_str(), ci.miou[0], ci.miou[1],
                  ci.weed_iou[0], ci.weed_iou[1], ci.recall[0], ci.recall[1],
                  ci.crop_only_left_dry[0], ci.crop_only_left_dry[1]);
    }
    return;
  }
  std::printf("plant masks: vegetation (crop or weed) IoU per image, averaged\n\n");
  std::printf("%-11s %8s %9s\n", "weed_source", "veg_IoU", "ms/image");
  for (const WeedEvalRow& row : rows) {
    std::printf("%-11s %8.4f %9.2f\n", std::string(to_string(row.source)).c_str(),
                row.vegetation_iou, row.ms_per_image);
  }
}

// The sprayer's dial: recall and clean zones left dry over decision thresholds.
// The sprayer's dial: recall and clean zones left dry over decision thresholds, and the
// threshold (searched in steps of 0.0001 up to 0.05) that leaves most zones dry at the recall
// target.
void print_sweep(const std::vector<WeedEvalRow>& rows, const ZoneRule& zones) {
  constexpr double kThresholds[] = {0.0,    0.0005, 0.001, 0.0015, 0.002,
                                    0.0025, 0.005,  0.01,  0.02,   0.05};
  constexpr double kRecallTarget = 0.95;
  const auto tally_at = [&](const WeedEvalRow& row, double threshold) {
    ZoneRule rule = zones;
    rule.decision_threshold = threshold;
    return tally_zones(row.zone_samples, rule);
  };
  std::printf(
      "\nzone trade-off by decision threshold (recall / crop-only zones left dry / bare zones "
      "left dry)\n%-11s",
      "weed_source");
  for (double threshold : kThresholds) std::printf(" %19.4f", threshold);
  std::printf("   most crop-only zones dry with recall >= %.2f\n", kRecallTarget);
  for (const WeedEvalRow& row : rows) {
    std::printf("%-11s", std::string(to_string(row.source)).c_str());
    for (double threshold : kThresholds) {
      const ZoneTally tally = tally_at(row, threshold);
      std::printf("   %.3f/%.3f/%.3f", tally.recall(), tally.crop_only_left_dry(),
                  tally.bare_left_dry());
    }
    double best_threshold = -1;
    ZoneTally best;
    for (int step = 0; step <= 500; ++step) {
      const double threshold = step * 0.0001;
      const ZoneTally tally = tally_at(row, threshold);
      if (tally.recall() >= kRecallTarget &&
          (best_threshold < 0 || tally.crop_only_left_dry() > best.crop_only_left_dry())) {
        best_threshold = threshold;
        best = tally;
      }
    }
    if (best_threshold < 0) {
      std::printf("   none\n");
    } else {
      std::printf("   %.4f: %.3f/%.3f/%.3f\n", best_threshold, best.recall(),
                  best.crop_only_left_dry(), best.bare_left_dry());
    }
  }
}

}  // namespace

int run_weed_eval(const WeedEvalOptions& options) {
  const Setup setup = setup_from(options);
  cv::setNumThreads(1);  // ms_per_image as on the daemon's camera worker
  const std::vector<std::string> stems =
      options.list.empty() ? std::vector<std::string>{} : read_stem_list(options.list);
  std::vector<LabelledImage> images =
      load_labelled_images(options.images_dir, options.masks_dir, stems);
  if (options.frame_mm_per_px > 0) {
    resample_to_scale(images, setup.image_mm_per_px, options.frame_mm_per_px);
  }
  std::vector<WeedEvalRow> rows;
  for (const vision::WeedSource source : setup.sources) {
    vision::PipelineConfig config = setup.base;
    config.weed_source = source;
    rows.push_back(
        evaluate_weed_source(images, config, setup.onnx, setup.zones, options.class_masks));
  }
  if (options.json) {
    print_json(images.size(), rows, setup.zones, options.class_masks);
  } else {
    print_table(options, images.size(), rows, setup);
    if (options.sweep && options.class_masks) print_sweep(rows, setup.zones);
  }
  return 0;
}

}  // namespace weedspray::lab
