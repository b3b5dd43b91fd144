// SPDX-License-Identifier: Apache-2.0
// experiment savings: liquid saved by variable-rate spraying at equal coverage on a field laid
// out from labelled crop/weed photos; --plants: over drawn machines as made.
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "lab/experiment_commands/experiment_command.hpp"
#include "lab/experiment_commands/spread_table.hpp"
#include "lab/experiment_field.hpp"
#include "lab/report/report.hpp"
#include "lab/vision_dataset.hpp"
#include "lab/weed_eval_command.hpp"
#include "lab/weed_model.hpp"

namespace weedspray::lab {
namespace {

namespace ex = lab::experiments;

// The savings field's weed densities: the masks' true weed share ("truth"), or what a weed
// source of the vision pipeline reports on the photos.
LabelledField savings_field(const ExperimentOptions& o, const std::vector<LabelledImage>& images) {
  if (o.weed_source == "truth") {
    if (!o.model.empty()) throw std::runtime_error("--model needs a --weed-source dnn or hybrid");
    return labelled_field(images, std::nullopt);
  }
  vision::PipelineConfig config = vision::default_pipeline_config();
  config.weed_source = parse_weed_source_option("--weed-source", o.weed_source);
  config.crop_margin_px = kDefaultCropMarginPx;
  std::vector<std::uint8_t> onnx;
  if (vision::needs_model(config.weed_source)) {
    if (o.model.empty()) {
      throw std::runtime_error("--weed-source " + o.weed_source + " needs --model FILE");
    }
    WeedModel model = read_weed_model(o.model);
    config.dnn = model.spec;
    onnx = std::move(model.onnx);
  }
  return labelled_field(images, config, onnx);
}

void report_fleet(const ExperimentOptions& o, const ex::SavingsFleetResult& f, std::size_t photos,
                  const ex::SavingsOptions& options) {
  Report report = fleet_report(o.plants, o.seed);
  report.json()
      .add("changed_after_calibration", Json::boolean(false))
      .add("images", Json::unsigned_integer(photos))
      .add("weed_source", Json::string(o.weed_source))
      .add("decision_threshold", Json::number(options.decision_threshold, "%.4f"));
  report.line(
      "savings at equal coverage, %zu photos, weed density: %s, %d drawn machines (seed "
      "%llu) as made",
      photos, o.weed_source.c_str(), o.plants, static_cast<unsigned long long>(o.seed));
  SpreadTable("over the machines")
      .row("savings_pct", "savings [%] (worst = lowest)", f.savings_pct, "%12.2f")
      .row("under_dosed_pct", "under-dosed nozzle-zones [%]", f.under_dosed_pct, "%12.2f")
      .row("uniform_l", "uniform [L]", f.uniform_l, "%12.3f")
      .row("variable_l", "variable [L]", f.variable_l, "%12.3f")
      .report_to(report);
  report.print(o.json);
}

}  // namespace

int run_savings_command(const ExperimentOptions& o) {
  const char* data = std::getenv("WEEDSPRAY_DATA_DIR");
  const std::string peanut = std::string(data ? data : WEEDSPRAY_DEFAULT_DATA_DIR) + "/peanut";
  const std::string images = o.images_dir.empty() ? peanut + "/images" : o.images_dir;
  const std::string masks = o.masks_dir.empty() ? peanut + "/masks" : o.masks_dir;
  const std::vector<LabelledImage> photos = load_labelled_images(
      images, masks,
      o.stems_file.empty() ? std::vector<std::string>{} : read_stem_list(o.stems_file));
  const LabelledField field = savings_field(o, photos);
  ex::SavingsOptions options;
  options.seed = o.seed;
  // Weed densities are pixel shares (a few %), so the law's density scale and the decision
  // threshold are the daemon's (spray.max_density, spray.decision_threshold), not the wheat
  // paper's canopy figures.
  options.max_density = 1.0;
  options.decision_threshold =
      o.decision_threshold >= 0 ? o.decision_threshold : default_decision_threshold();
  if (o.plants > 0) {
    report_fleet(o, ex::run_savings_fleet(field.weed_density, {o.seed, o.plants, false}, options),
                 photos.size(), options);
    return 0;
  }
  const ex::SavingsResult r = ex::run_savings(field.weed_density, options);
  const ex::SavingsRun& clamp = r.spec_clamp;
  const ex::TruthTally equal_truth = ex::tally_against_truth(r.equal_coverage, field.truth);
  const ex::TruthTally clamp_truth = ex::tally_against_truth(clamp, field.truth);
  Report report;
  // Headline = equal coverage (every zone above the decision threshold sprayed at least at the
  // minimum duty); spec_clamp_* = the SPEC clamp (< 20 % duty -> closed).
  Json nozzle_savings = Json::array();
  for (const double pct : r.nozzle_savings_pct) nozzle_savings.push(Json::number(pct, "%.2f"));
  report.json()
      .add("images", Json::unsigned_integer(photos.size()))
      .add("weed_source", Json::string(o.weed_source))
      .add("decision_threshold", Json::number(options.decision_threshold, "%.4f"))
      .add("savings_pct", Json::number(r.savings_pct, "%.3f"))
      .add("weedy_zones", Json::integer(equal_truth.weedy_zones))
      .add("weedy_left_dry", Json::integer(equal_truth.weedy_left_dry))
      .add("crop_only_zones", Json::integer(equal_truth.crop_only_zones))
      .add("crop_only_sprayed", Json::integer(equal_truth.crop_only_sprayed))
      .add("under_dosed_zones", Json::integer(r.under_dosed_zones))
      .add("zones", Json::integer(r.zones))
      .add("variable_l", Json::number(r.variable_l, "%.4f"))
      .add("uniform_l", Json::number(r.uniform_l, "%.4f"))
      .add("nozzle_savings_pct", std::move(nozzle_savings))
      .add("policy", Json::string("equal_coverage"))
      .add("spec_clamp_savings_pct", Json::number(clamp.savings_pct, "%.3f"))
      .add("spec_clamp_weedy_left_dry", Json::integer(clamp_truth.weedy_left_dry))
      .add("spec_clamp_crop_only_sprayed", Json::integer(clamp_truth.crop_only_sprayed))
      .add("spec_clamp_under_dosed_zones", Json::integer(clamp.under_dosed_zones))
      .add("spec_clamp_variable_l", Json::number(clamp.variable_l, "%.4f"))
      .add("scheduler", Json::string("NozzleScheduler"));
  report.line(
      "field: %zu zones of %.1f m x 4 nozzles from %zu photos in %s%s%s (2x4 grid per "
      "photo), weed density: %s, decision threshold %.3f",
      field.weed_density.size(), options.zone_length_m, photos.size(), images.c_str(),
      o.stems_file.empty() ? "" : " listed in ", o.stems_file.c_str(), o.weed_source.c_str(),
      options.decision_threshold);
  report.line("truth (%s): %d weedy nozzle-zones (true weed >= 0.5 %%), %d crop-only nozzle-zones",
              masks.c_str(), equal_truth.weedy_zones, equal_truth.crop_only_zones);
  report.line("decisions pinned to ground intervals by the NozzleScheduler (1.2 m boom)");
  report.line("uniform %.3f L", r.uniform_l);
  report.line(
      "equal coverage (weedy zones >= min duty): variable %.3f L  savings %.1f %%  weedy left "
      "dry %d  crop-only sprayed %d  under-dosed %d of %d",
      r.variable_l, r.savings_pct, equal_truth.weedy_left_dry, equal_truth.crop_only_sprayed,
      r.under_dosed_zones, r.zones);
  report.line(
      "SPEC clamp (< 20 %% duty closed):         variable %.3f L  savings %.1f %%  weedy left "
      "dry %d  crop-only sprayed %d  under-dosed %d of %d",
      clamp.variable_l, clamp.savings_pct, clamp_truth.weedy_left_dry,
      clamp_truth.crop_only_sprayed, clamp.under_dosed_zones, r.zones);
  report.line("per nozzle savings (equal coverage) %.1f %.1f %.1f %.1f %% (paper: 46.3 %%)",
              r.nozzle_savings_pct[0], r.nozzle_savings_pct[1], r.nozzle_savings_pct[2],
              r.nozzle_savings_pct[3]);
  report.print(o.json);

  if (!o.plot.empty()) {
    PlotSpec spec{"Liquid per zone along the track", "distance [m]", "volume per zone [L]", {}};
    PlotSeries target{"law's target", {}, {}, kGrey};
    PlotSeries got{"delivered (true)", {}, {}, kBlue};
    for (std::size_t i = 0; i < r.zone_target_l.size(); ++i) {
      const double x = static_cast<double>(i) * options.zone_length_m;
      target.x.push_back(x);
      target.y.push_back(r.zone_target_l[i]);
      got.x.push_back(x);
      got.y.push_back(r.zone_delivered_l[i]);
    }
    spec.series = {target, got};
    write_plot_png(spec, o.plot);
  }
  return 0;
}

}  // namespace weedspray::lab
