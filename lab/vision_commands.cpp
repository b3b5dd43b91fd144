// SPDX-License-Identifier: Apache-2.0
// weedspray-lab vision subcommands: vision-eval (index x threshold, or the weed sources with
// --classes / --weed-sources), segment, bench-vision.
#include <cstdio>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include "lab/commands.hpp"
#include "lab/vision_eval.hpp"
#include "lab/vision_tools.hpp"
#include "lab/weed_eval_command.hpp"
#include "lab/weed_model.hpp"

namespace weedspray::lab {
namespace {

struct EvalOptions {
  WeedEvalOptions weeds;  // images, masks, list and json live here
  bool weed_sources = false;
  bool bounds = false;
  bool keep_split = false;
  std::string unimodal;  // empty: each index's default
  int peak_margin = -1;  // < 0: the library's
};

// "unimodal policy: ..." for the table's heading.
std::string unimodal_policy_text(const vision::ThresholdParams& params) {
  if (params.unimodal != vision::UnimodalPolicy::kIndexDefault) {
    return std::string(to_string(params.unimodal));
  }
  const vision::VegetationIndex index = vision::default_pipeline_config().index;
  return "each index's default (" + std::string(to_string(index)) + ": " +
         std::string(to_string(vision::default_unimodal_policy(index))) + ")";
}

int run_vision_eval(const EvalOptions& all) {
  if (all.weeds.class_masks || all.weed_sources) return run_weed_eval(all.weeds);
  const WeedEvalOptions& options = all.weeds;
  const std::vector<std::string> stems =
      options.list.empty() ? std::vector<std::string>{} : read_stem_list(options.list);
  const std::vector<LabelledImage> images =
      load_labelled_images(options.images_dir, options.masks_dir, stems);
  vision::PipelineConfig base = vision::default_pipeline_config();
  if (all.keep_split) base.threshold_params.unimodal = vision::UnimodalPolicy::kKeepSplit;
  if (!all.unimodal.empty()) {
    const auto policy = vision::parse_unimodal_policy(all.unimodal);
    if (!policy) {
      throw std::runtime_error("--unimodal: unknown policy '" + all.unimodal +
                               "' (index_default, clear_of_peak, fixed_scale, keep_split)");
    }
    base.threshold_params.unimodal = *policy;
  }
  if (all.peak_margin >= 0) base.threshold_params.peak_margin = all.peak_margin;
  const std::vector<EvalRow> rows = evaluate_combinations(images, vision::all_vegetation_indices(),
                                                          vision::all_threshold_methods(), base);
  const vision::PipelineConfig defaults = vision::default_pipeline_config();
  if (options.json) {
    std::printf("{\"images\": %zu, \"results\": [", images.size());
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const EvalRow& row = rows[i];
      std::printf(
          "%s{\"index\": \"%s\", \"threshold\": \"%s\", \"mean_iou\": %.4f, \"mean_threshold\": "
          "%.3f, \"threshold_error\": %.4f, \"precision_pct\": %.3f, \"ms_per_image\": %.4f}",
          i == 0 ? "" : ", ", std::string(to_string(row.index)).c_str(),
          std::string(to_string(row.threshold)).c_str(), row.mean_iou, row.mean_threshold,
          row.threshold_error, row.precision_pct, row.ms_per_image);
    }
    std::printf("], \"default\": {\"index\": \"%s\", \"threshold\": \"%s\"}}\n",
                std::string(to_string(defaults.index)).c_str(),
                std::string(to_string(defaults.threshold)).c_str());
    return 0;
  }
  std::printf("%zu images from %s (unimodal policy: %s, peak margin %d)\n\n", images.size(),
              options.images_dir.c_str(), unimodal_policy_text(base.threshold_params).c_str(),
              base.threshold_params.peak_margin);
  std::printf("%-11s %-9s %8s %9s %9s %10s %9s\n", "index", "threshold", "mean_IoU", "mean_T",
              "eps_otsu", "rho_otsu_%", "ms/image");
  for (const EvalRow& row : rows) {
    const bool is_default = row.index == defaults.index && row.threshold == defaults.threshold;
    std::printf(
        "%-11s %-9s %8.4f %9.2f %9.3f %10.2f %9.3f%s\n", std::string(to_string(row.index)).c_str(),
        std::string(to_string(row.threshold)).c_str(), row.mean_iou, row.mean_threshold,
        row.threshold_error, row.precision_pct, row.ms_per_image, is_default ? "  <- default" : "");
  }
  if (all.bounds) {
    std::printf("\nupper bounds per index: best threshold per image / best shared threshold\n");
    for (const vision::VegetationIndex index : vision::all_vegetation_indices()) {
      const IndexBounds bounds = index_bounds(images, index);
      std::printf("%-11s oracle %.4f   fixed %.4f at T=%d\n", std::string(to_string(index)).c_str(),
                  bounds.oracle_iou, bounds.best_fixed_iou, bounds.best_fixed);
    }
  }
  return 0;
}

}  // namespace

void add_vision_commands(CLI::App& app) {
  auto eval_options = std::make_shared<EvalOptions>();
  WeedEvalOptions& weeds = eval_options->weeds;
  CLI::App* eval = app.add_subcommand(
      "vision-eval",
      "Every vegetation index x threshold against hand-labelled masks; with --classes or "
      "--weed-sources, the weed sources (vegetation, inter_row, dnn, hybrid, plants, "
      "dnn_vegetation)");
  eval->add_option("--images", weeds.images_dir, "Folder of field images")
      ->required()
      ->check(CLI::ExistingDirectory);
  eval->add_option("--masks", weeds.masks_dir,
                   "Folder of masks (PNG, same stem as the image, non-zero = plant; with "
                   "--classes, class ids 0 soil, 1 crop, 2 weed)")
      ->required()
      ->check(CLI::ExistingDirectory);
  eval->add_option("--list", weeds.list,
                   "Evaluate only the image stems listed in this file (one per line), e.g. "
                   "tools/train/splits/peanut-val.txt")
      ->check(CLI::ExistingFile);
  eval->add_flag("--json", weeds.json, "Print one JSON object");
  eval->add_flag("--classes", weeds.class_masks,
                 "Masks hold class ids: evaluate the weed sources (IoU per class, MIoU, MPA, "
                 "zone recall and clean zones left dry)");
  eval->add_flag("--weed-sources", eval_options->weed_sources,
                 "Evaluate the weed sources' vegetation (crop or weed) against plant masks");
  eval->add_option(
          "--model", weeds.model,
          "ONNX weed model (spec from FILE.json): adds dnn, hybrid, plants and dnn_vegetation")
      ->check(CLI::ExistingFile);
  eval->add_option("--weed-source", weeds.weed_source,
                   "Evaluate only this source: " + weed_source_list());
  eval->add_option("--config", weeds.config,
                   "weedsprayd configuration: [vision] keys of the first camera, its model and "
                   "spray.decision_threshold")
      ->check(CLI::ExistingFile);
  eval->add_option("--grid", weeds.grid, "Zone grid ROWSxCOLS (default: the daemon's 2x4)");
  eval->add_option("--decision-threshold", weeds.decision_threshold,
                   "Weed density at which a zone is sprayed (default: the daemon's "
                   "spray.decision_threshold)");
  eval->add_flag("--sweep", weeds.sweep,
                 "With --classes: also the zone trade-off over a range of decision thresholds");
  eval->add_option("--image-mm-per-px", weeds.image_mm_per_px,
                   "Ground mm per pixel of the images (default: the model's training photos', "
                   "its JSON's training.dataset_mm_per_px); frames are resampled to the model's "
                   "ground scale as the daemon does");
  eval->add_option("--frame-mm-per-px", weeds.frame_mm_per_px,
                   "Resample the images and masks to this ground scale first, as a camera at "
                   "that scale sees the same ground (the daemon's default camera: 1.0077)");
  eval->add_option("--weedy-share", weeds.weedy_share,
                   "A zone is weedy when at least this share of it is weed")
      ->capture_default_str();
  eval->add_option("--crop-margin-px", weeds.crop_margin_px,
                   "hybrid: crop mask grown by this many pixels (default: vision.crop_margin_cm, "
                   "the daemon's or --config's, at the images' ground scale; " +
                       std::to_string(kDefaultCropMarginPx) + " where that is unknown)");
  eval->add_option("--min-plant-px", weeds.min_plant_px,
                   "plants: smaller connected vegetation is a speck (default: "
                   "vision.min_plant_cm2, the daemon's or --config's, at the images' ground "
                   "scale; " +
                       std::to_string(kDefaultMinPlantPx) + " where that is unknown)");
  eval->add_option("--row-band", weeds.row_band_fraction,
                   "inter_row: crop-row band width as a share of the frame width");
  eval->add_flag("--bounds", eval_options->bounds,
                 "Also print per-index IoU upper bounds (best threshold per image / shared)");
  eval->add_flag("--keep-split", eval_options->keep_split,
                 "Keep each method's split on unimodal histograms (the papers' behaviour; "
                 "= --unimodal keep_split)");
  eval->add_option("--unimodal", eval_options->unimodal,
                   "What frames that do not look bimodal get: index_default (CIVE, raw ExG: "
                   "clear_of_peak; others: fixed_scale) | clear_of_peak | fixed_scale | "
                   "keep_split");
  eval->add_option("--peak-margin", eval_options->peak_margin,
                   "clear_of_peak: levels above the histogram peak that are still soil "
                   "(default 3)")
      ->check(CLI::Range(0, 255));
  eval->callback(
      [eval_options] { run_reporting_errors([&] { return run_vision_eval(*eval_options); }); });

  add_segment_command(app);
  add_bench_vision_command(app);
}

}  // namespace weedspray::lab
