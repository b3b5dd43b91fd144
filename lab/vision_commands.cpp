// weedspray-lab vision subcommands: vision-eval, segment, bench-vision.
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "lab/commands.hpp"
#include "lab/vision_eval.hpp"
#include "lab/vision_tools.hpp"

namespace weedspray::lab {
namespace {

struct EvalOptions {
  std::string images_dir;
  std::string masks_dir;
  bool json = false;
  bool bounds = false;
  bool keep_split = false;
};

int run_vision_eval(const EvalOptions& options) {
  const std::vector<LabelledImage> images =
      load_labelled_images(options.images_dir, options.masks_dir);
  vision::PipelineConfig base = vision::default_pipeline_config();
  if (options.keep_split) base.threshold_params.unimodal = vision::UnimodalPolicy::kKeepSplit;
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
  std::printf("%zu images from %s (unimodal policy: %s)\n\n", images.size(),
              options.images_dir.c_str(), options.keep_split ? "keep split" : "fixed scale");
  std::printf("%-11s %-9s %8s %9s %9s %10s %9s\n", "index", "threshold", "mean_IoU", "mean_T",
              "eps_otsu", "rho_otsu_%", "ms/image");
  for (const EvalRow& row : rows) {
    const bool is_default = row.index == defaults.index && row.threshold == defaults.threshold;
    std::printf(
        "%-11s %-9s %8.4f %9.2f %9.3f %10.2f %9.3f%s\n", std::string(to_string(row.index)).c_str(),
        std::string(to_string(row.threshold)).c_str(), row.mean_iou, row.mean_threshold,
        row.threshold_error, row.precision_pct, row.ms_per_image, is_default ? "  <- default" : "");
  }
  if (options.bounds) {
    std::printf("\nupper bounds per index: best threshold per image / best shared threshold\n");
    for (const vision::VegetationIndex index : vision::all_vegetation_indices()) {
      const IndexBounds bounds = index_bounds(images, index);
      std::printf("%-11s oracle %.4f   fixed %.4f at T=%d\n", std::string(to_string(index)).c_str(),
                  bounds.oracle_iou, bounds.best_fixed_iou, bounds.best_fixed);
    }
  }
  return 0;
}

// CLI11 callbacks cannot return an exit code: errors become CLI::RuntimeError after a clear
// message naming the file or argument.
template <typename Function>
void run_reporting_errors(Function&& function) {
  int code = 0;
  try {
    code = function();
  } catch (const std::exception& error) {
    std::cerr << "weedspray-lab: " << error.what() << "\n";
    code = 1;
  }
  if (code != 0) throw CLI::RuntimeError(code);
}

}  // namespace

void add_vision_commands(CLI::App& app) {
  auto eval_options = std::make_shared<EvalOptions>();
  CLI::App* eval = app.add_subcommand(
      "vision-eval", "Every vegetation index x threshold against hand-labelled masks");
  eval->add_option("--images", eval_options->images_dir, "Folder of field images")
      ->required()
      ->check(CLI::ExistingDirectory);
  eval->add_option("--masks", eval_options->masks_dir,
                   "Folder of masks (PNG, same stem as the image, non-zero = plant)")
      ->required()
      ->check(CLI::ExistingDirectory);
  eval->add_flag("--json", eval_options->json, "Print one JSON object");
  eval->add_flag("--bounds", eval_options->bounds,
                 "Also print per-index IoU upper bounds (best threshold per image / shared)");
  eval->add_flag("--keep-split", eval_options->keep_split,
                 "Keep each method's split on unimodal histograms (the papers' behaviour)");
  eval->callback(
      [eval_options] { run_reporting_errors([&] { return run_vision_eval(*eval_options); }); });

  add_segment_command(app);
  add_bench_vision_command(app);
}

}  // namespace weedspray::lab
