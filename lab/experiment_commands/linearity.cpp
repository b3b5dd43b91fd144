// SPDX-License-Identifier: Apache-2.0
// experiment linearity: nozzle 1 swept 10-100 % while the others stay open, volume asked for
// against delivered; --plants: over drawn machines, calibrated as made, then changed.
#include "lab/experiment_commands/duty_points.hpp"
#include "lab/experiment_commands/experiment_command.hpp"
#include "lab/experiment_commands/spread_table.hpp"
#include "lab/report/report.hpp"

namespace weedspray::lab {
namespace {

namespace ex = lab::experiments;

int run_linearity_fleet_command(const ExperimentOptions& o) {
  const ex::SprayRunOptions base;
  const ex::LinearityFleetResult r = ex::run_linearity_fleet({o.seed, o.plants, true}, base);
  Report report = fleet_report(o.plants, o.seed);
  report.json()
      .add("changed_after_calibration", Json::boolean(true))
      .add("target_follows_speed", Json::boolean(base.follow_speed));
  report.line(
      "nozzle 1 swept 10-100 %%, 0.2 MPa, 3 Hz, %d drawn machines (seed %llu), "
      "calibrated as made, then changed; trim on",
      o.plants, static_cast<unsigned long long>(o.seed));
  SpreadTable("over the machines")
      .row("r2", "R2 (worst = lowest)", r.r2, "%12.5f")
      .row("mean_error_pct", "mean error [%]", r.mean_error_pct, "%12.3f")
      .row("max_error_pct", "max error [%]", r.max_error_pct, "%12.3f")
      .report_to(report);
  report.print(o.json);
  return 0;
}

}  // namespace

int run_linearity_command(const ExperimentOptions& o) {
  if (o.plants > 0) return run_linearity_fleet_command(o);
  ex::SprayRunOptions options;
  options.seed = o.seed;
  options.raw = o.raw;
  const ex::LinearityResult r = ex::run_linearity(options);
  Report report;
  report.json()
      .add("raw", Json::boolean(r.raw))
      .add("r2", Json::number(r.r2, "%.6f"))
      .add("mean_error_pct", Json::number(r.mean_error_pct, "%.4f"))
      .add("max_error_pct", Json::number(r.max_error_pct, "%.4f"));
  report.line("nozzle 1 swept, nozzles 2-4 at 100 %%, 0.2 MPa, 3 Hz, 30 s per point (%s)",
              spray_run_mode(r.raw));
  Table points = duty_point_table();
  for (const auto& p : r.points) points.row(duty_point_cells(p));
  report.table(points, "points");
  report.line("R2 %.5f  mean error %.2f %%  max error %.2f %%", r.r2, r.mean_error_pct,
              r.max_error_pct);
  report.print(o.json);

  if (!o.plot.empty()) {
    PlotSpec spec{"Nozzle 1 volume in 30 s vs duty", "duty [%]", "volume [L]", {}};
    const auto duty = [](const auto& p) { return p.duty_pct; };
    spec.series = {series_of(r.points, "requested", kGrey, false, duty,
                             [](const auto& p) { return p.requested_l; }),
                   series_of(r.points, "delivered (true)", kBlue, true, duty,
                             [](const auto& p) { return p.delivered_l; })};
    write_plot_png(spec, o.plot);
  }
  return 0;
}

}  // namespace weedspray::lab
