// SPDX-License-Identifier: Apache-2.0
// weedspray-lab experiment NAME [--json] [--plot OUT.png] [--raw] [--seed N] [--tune]
// Reruns the papers' experiments on the simulated machine (lab/experiments/); each NAME's
// command is its own file in this folder.
#include <array>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "lab/commands.hpp"
#include "lab/experiment_commands/experiment_command.hpp"

namespace weedspray::lab {
namespace {

struct ExperimentCommand {
  const char* name;
  int (*run)(const ExperimentOptions&);
};

// In the order --help lists them.
constexpr std::array kExperimentCommands{
    ExperimentCommand{"step", run_step_command},
    ExperimentCommand{"ripple", run_ripple_command},
    ExperimentCommand{"linearity", run_linearity_command},
    ExperimentCommand{"orthogonal", run_orthogonal_command},
    ExperimentCommand{"dose", run_dose_command},
    ExperimentCommand{"calibrate", run_calibrate_command},
    ExperimentCommand{"savings", run_savings_command},
    ExperimentCommand{"blockage", run_blockage_command},
    ExperimentCommand{"field-dose", run_field_dose_command},
};

int run_experiment(const ExperimentOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  int rc = 0;
  for (const ExperimentCommand& command : kExperimentCommands)
    if (o.name == command.name) rc = command.run(o);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.json) std::printf("(wall time %.2f s)\n", wall);
  if (!o.plot.empty()) std::fprintf(stderr, "plot written to %s\n", o.plot.c_str());
  return rc;
}

}  // namespace

void add_experiment_commands(CLI::App& app) {
  auto options = std::make_shared<ExperimentOptions>();
  CLI::App* cmd = app.add_subcommand(
      "experiment", "rerun a paper's experiment on the simulated sprayer (hydraulic plant model)");
  std::vector<std::string> names;
  std::string names_help;
  for (const ExperimentCommand& command : kExperimentCommands) {
    names_help += names.empty() ? "" : " | ";
    names_help += command.name;
    names.emplace_back(command.name);
  }
  cmd->add_option("name", options->name, names_help)->required()->check(CLI::IsMember(names));
  cmd->add_flag("--json", options->json, "print one JSON object instead of a table");
  cmd->add_option("--plot", options->plot, "write the figure to this PNG file");
  cmd->add_flag("--raw", options->raw,
                "linearity/orthogonal: no calibration, compensation or flow feedback; "
                "synchronous PWM");
  cmd->add_flag("--tune", options->tune, "step: rerun the gain search before the comparison");
  cmd->add_option("--seed", options->seed, "plant seed (nozzle spread, valve delays, noise)");
  cmd->add_option("--tune-budget", options->tune_budget,
                  "step --plants --tune: evaluations per controller (same for both)")
      ->check(CLI::Range(10, 100000));
  cmd->add_option("--plants", options->plants,
                  "every experiment (savings: machines as made): over N machines drawn from "
                  "documented spreads (seed "
                  "--seed); prints mean, sd and worst")
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--control-period-ms", options->control_period_ms,
                  "step: pressure loop period (one machine: 5 ms unless given; --plants: the "
                  "daemon's 10 ms)")
      ->check(CLI::Range(0.1, 100.0));
  cmd->add_option("--converter-lead-ms", options->converter_lead_ms,
                  "step: ADC sampled this long before each tick (the daemon's converters' thread: "
                  "up to half a period)")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--converter-lag-ms", options->converter_lag_ms,
                  "step: DAC written this long after each tick (the daemon: 1 ms)")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--images", options->images_dir,
                  "savings: labelled field photos (default $WEEDSPRAY_DATA_DIR/peanut/images)");
  cmd->add_option("--masks", options->masks_dir,
                  "savings: their class-id masks, 0 soil 1 crop 2 weed (default "
                  "$WEEDSPRAY_DATA_DIR/peanut/masks)");
  cmd->add_option("--stems", options->stems_file,
                  "savings: only the photos listed in this file, one stem a line (e.g. "
                  "tools/train/splits/peanut-val.txt: photos a shipped model never saw)");
  cmd->add_option("--weed-source", options->weed_source,
                  "savings: weed density the sprayer acts on: truth (the masks' weed share, the "
                  "best any detector can do) | vegetation | inter_row | dnn | hybrid");
  cmd->add_option("--model", options->model,
                  "savings: ONNX model for --weed-source dnn|hybrid (spec from its .json)");
  cmd->add_option("--decision-threshold", options->decision_threshold,
                  "savings: zones with a weed density below this are not sprayed (default: the "
                  "daemon's spray.decision_threshold)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--change-parts", options->change_parts,
                  "orthogonal --plants: the drawn change after calibration, all of it, only its "
                  "common part (meter drift, supply and speed ramps), only its per-nozzle part "
                  "(wear, ageing, the blockage), or none (as made)")
      ->check(CLI::IsMember({"all", "common", "nozzle", "none"}));
  cmd->add_option("--health-judge", options->health_judge,
                  "blockage: the nozzle health judge: recheck (the default: each nozzle held "
                  "open alone on the headlands, control/nozzle_recheck.hpp; field duties only) "
                  "or band / cusum (passive, on the spraying, control/nozzle_health.hpp)")
      ->check(CLI::IsMember({"band", "cusum", "recheck"}));
  cmd->add_option("--duties", options->duties,
                  "blockage: the nozzles' requested duties: field (a field's weed patches, "
                  "closures, headlands and speed, sim/field/field_duty_process.hpp) or iid (each "
                  "redrawn between 30 and 90 % every second)")
      ->check(CLI::IsMember({"field", "iid"}));
  cmd->add_option("--blockage", options->blockage,
                  "blockage: the share of the blocked nozzle's flow lost (default 0.2)")
      ->check(CLI::Range(0.01, 0.99));
  cmd->add_flag("--blocked-at-start", options->blocked_at_start,
                "blockage: the nozzle is blocked before the job starts (no healthy part)");
  cmd->callback([options] {
    try {
      const int rc = run_experiment(*options);
      if (rc != 0) throw CLI::RuntimeError(rc);
    } catch (const CLI::Error&) {
      throw;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "experiment %s: %s\n", options->name.c_str(), e.what());
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace weedspray::lab
