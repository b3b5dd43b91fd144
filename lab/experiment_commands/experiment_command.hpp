// SPDX-License-Identifier: Apache-2.0
// One weedspray-lab experiment subcommand per source file in this folder: each runs its
// experiment (lab/experiments/) and reports it through a Report (lab/report/report.hpp);
// lab/experiment_commands/register.cpp names them and parses the options.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lab/experiment_plot.hpp"
#include "lab/experiments/experiments.hpp"

namespace weedspray::lab {

struct ExperimentOptions {
  std::string name;
  bool json = false;
  std::string plot;
  bool raw = false;
  bool tune = false;
  int tune_budget = 300;
  std::uint64_t seed = 1;
  int plants = 0;  // > 0: over this many drawn machines (lab/experiments/machines.hpp)
  std::string images_dir;
  std::string masks_dir;
  std::string stems_file;
  std::string weed_source = "truth";
  std::string model;
  double decision_threshold = -1.0;      // < 0: the daemon's spray.decision_threshold default
  std::string health_judge = "recheck";  // blockage: recheck | band | cusum (NozzleHealth)
  std::string duties = "field";          // blockage: the requested duties (field | iid)
  std::optional<double> blockage;        // blockage: its flow lost; unset: BlockageOptions
  bool blocked_at_start = false;         // blockage: blocked before the job, no healthy part
  std::string change_parts = "all";      // orthogonal --plants: which part of the change
  // step: the pressure loop's timing; unset: 5 / 0 / 0 ms for one machine, the daemon's
  // (10 / 2.5 / 1 ms) for --plants.
  std::optional<double> control_period_ms;
  std::optional<double> converter_lead_ms;
  std::optional<double> converter_lag_ms;
};

// Each returns the exit code; throws std::exception with a message on bad input.
int run_step_command(const ExperimentOptions& o);
int run_ripple_command(const ExperimentOptions& o);
int run_calibrate_command(const ExperimentOptions& o);
int run_linearity_command(const ExperimentOptions& o);
int run_orthogonal_command(const ExperimentOptions& o);
int run_dose_command(const ExperimentOptions& o);
int run_blockage_command(const ExperimentOptions& o);
int run_savings_command(const ExperimentOptions& o);
int run_field_dose_command(const ExperimentOptions& o);

// ---------- figures ----------

inline constexpr int kBlue = 0x1f77b4, kOrange = 0xff7f0e, kGreen = 0x2ca02c, kRed = 0xd62728,
                     kGrey = 0x7f7f7f;

// One plot series from a list of points, x and y picked by the two projections.
template <class Points, class X, class Y>
PlotSeries series_of(const Points& points, std::string name, int rgb, bool markers, X x_of,
                     Y y_of) {
  PlotSeries s{std::move(name), {}, {}, rgb, markers};
  for (const auto& p : points) {
    s.x.push_back(x_of(p));
    s.y.push_back(y_of(p));
  }
  return s;
}

inline PlotSeries pressure_series(const std::vector<lab::experiments::TraceSample>& trace,
                                  const std::string& name, int rgb, double t_offset = 0.0) {
  return series_of(
      trace, name, rgb, false, [&](const auto& p) { return p.time_s - t_offset; },
      [](const auto& p) { return p.pressure_mpa; });
}

}  // namespace weedspray::lab
