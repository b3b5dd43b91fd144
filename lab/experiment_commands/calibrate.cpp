// SPDX-License-Identifier: Apache-2.0
// experiment calibrate: the flow meter's catch test, then each nozzle's line q = A s + b
// alone on the one meter; --plants: over drawn machines as made.
#include <string>

#include "lab/experiment_commands/experiment_command.hpp"
#include "lab/experiment_commands/spread_table.hpp"
#include "lab/report/report.hpp"

namespace weedspray::lab {
namespace {

namespace ex = lab::experiments;

int run_calibrate_fleet_command(const ExperimentOptions& o) {
  const ex::CalibrationFleetResult r = ex::run_calibration_fleet({o.seed, o.plants, false});
  Report report = fleet_report(o.plants, o.seed);
  report.line(
      "catch test + per-nozzle lines (each nozzle alone, one line meter), 0.2 MPa, 3 Hz, "
      "%d drawn machines as made (seed %llu)",
      o.plants, static_cast<unsigned long long>(o.seed));
  SpreadTable("over the machines")
      .row("meter_error_pct", "meter K error after catch [%]", r.meter_error_pct, "%12.4f")
      .row("full_open_error_pct", "worst nozzle full-open error [%]", r.full_open_error_pct,
           "%12.3f")
      .row("line_error_pct", "worst nozzle line error 20-80 [%]", r.line_error_pct, "%12.3f")
      .row("r2", "lowest nozzle R2", r.r2, "%12.5f")
      .report_to(report);
  report.print(o.json);
  return 0;
}

// Each nozzle's fitted line against the truth.
Table nozzle_table() {
  return Table({{"", "nozzle", 6, "%6zu", ""},
                {"a", "A", 10, "%10.6f", "%.6f"},
                {"b", "b", 8, "%8.5f", "%.5f"},
                {"true_a", "true A", 10, "%10.6f", "%.6f"},
                {"true_b", "true b", 8, "%8.5f", "%.5f"},
                {"r2", "R2", 9, "%9.6f", "%.6f"},
                {"full_open_l_per_min", "full-open", 10, "%10.5f", "%.5f"},
                {"true_full_open_l_per_min", "true full", 10, "%10.5f", "%.5f"}});
}

}  // namespace

int run_calibrate_command(const ExperimentOptions& o) {
  if (o.plants > 0) return run_calibrate_fleet_command(o);
  ex::CalibrationOptions options;
  options.seed = o.seed;
  const ex::CalibrationResult r = ex::run_calibration(options);
  Report report;
  report.json()
      .add("meter_k_error_pct", Json::number(r.meter_k_error_pct, "%.4f"))
      .add("meter_pulses_per_litre", Json::number(r.meter.pulses_per_litre, "%.2f"))
      .add("true_pulses_per_litre", Json::number(r.true_pulses_per_litre, "%.2f"))
      .add("meter_calibration_error_pct", Json::number(r.meter_calibration_error_pct, "%.4f"))
      .add("jug_error_pct", Json::number(r.jug_error_pct, "%.4f"));
  report.line(
      "catch test: label 8500 pulses/L, measured %.1f, true %.1f (label error %.2f %%, "
      "calibration error %.3f %%, the jug read %+.3f %%)",
      r.meter.pulses_per_litre, r.true_pulses_per_litre, r.meter_k_error_pct,
      r.meter_calibration_error_pct, r.jug_error_pct);
  report.line("nozzle lines q = A s + b at %.2f MPa, %.0f Hz (each nozzle alone, one meter)",
              options.pressure_mpa, options.frequency_hz);
  Table nozzles = nozzle_table();
  for (std::size_t i = 0; i < r.nozzles.size(); ++i) {
    const auto& n = r.nozzles[i];
    nozzles.row({static_cast<long long>(i + 1), n.fitted.slope_l_per_min_per_pct,
                 n.fitted.intercept_l_per_min, n.truth.slope_l_per_min_per_pct,
                 n.truth.intercept_l_per_min, n.r_squared, n.full_open_l_per_min,
                 n.true_full_open_l_per_min});
  }
  report.table(nozzles, "nozzles");
  report.print(o.json);

  if (!o.plot.empty()) {
    PlotSpec spec{"Calibrated nozzle lines (markers: true flow at the calibration duties)",
                  "duty [%]",
                  "flow [L/min]",
                  {}};
    const int colours[] = {kBlue, kOrange, kGreen, kRed};
    for (std::size_t i = 0; i < r.nozzles.size(); ++i) {
      const auto& n = r.nozzles[i];
      PlotSeries line{"nozzle " + std::to_string(i + 1) + " fitted", {}, {}, colours[i % 4]};
      PlotSeries truth{"nozzle " + std::to_string(i + 1) + " true", {}, {}, colours[i % 4], true};
      for (double d : options.duties_pct) {
        line.x.push_back(d);
        line.y.push_back(n.fitted.slope_l_per_min_per_pct * d + n.fitted.intercept_l_per_min);
        truth.x.push_back(d);
        truth.y.push_back(n.truth.slope_l_per_min_per_pct * d + n.truth.intercept_l_per_min);
      }
      spec.series.push_back(line);
      spec.series.push_back(truth);
    }
    write_plot_png(spec, o.plot);
  }
  return 0;
}

}  // namespace weedspray::lab
