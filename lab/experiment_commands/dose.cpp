// SPDX-License-Identifier: Apache-2.0
// experiment dose: the wheat paper's dose check, nozzle 1's delivered flow against the law's
// at each weed density; --plants: over drawn machines, calibrated as made, then changed.
#include "lab/experiment_commands/experiment_command.hpp"
#include "lab/experiment_commands/spread_table.hpp"
#include "lab/report/report.hpp"

namespace weedspray::lab {
namespace {

namespace ex = lab::experiments;

int run_dose_fleet_command(const ExperimentOptions& o) {
  const ex::DoseOptions base;
  const ex::DoseFleetResult r = ex::run_dose_fleet({o.seed, o.plants, true}, base);
  Report report = fleet_report(o.plants, o.seed);
  report.json()
      .add("changed_after_calibration", Json::boolean(true))
      .add("target_follows_speed", Json::boolean(base.follow_speed))
      .add("speed_m_per_s", Json::object()
                                .add("min", Json::number(r.speed_min_m_per_s, "%.4g"))
                                .add("max", Json::number(r.speed_max_m_per_s, "%.4g")));
  report.line(
      "wheat paper dose check (densities 0.40-0.75, 0.4 MPa, 5 Hz, nozzle 1), %d drawn "
      "machines (seed %llu), each calibrated as made, then changed; the ground speed ramps "
      "(%.2f-%.2f m/s) and %s",
      o.plants, static_cast<unsigned long long>(o.seed), r.speed_min_m_per_s, r.speed_max_m_per_s,
      base.follow_speed ? "the law's target follows it" : "the target stays the law's at 1 m/s");
  SpreadTable table("over the machines");
  for (const auto* row : {&r.trim_on, &r.trim_off}) {
    const bool on = row == &r.trim_on;
    table.section(on ? "trim_on" : "trim_off", on ? "online flow trim ON" : "online flow trim OFF")
        .row("r2", "R2 (worst = lowest)", row->r2, "%12.5f")
        .row("mean_error_pct", "mean error [%]", row->mean_error_pct, "%12.3f")
        .row("max_error_pct", "max error [%]", row->max_error_pct, "%12.3f")
        .row("clipped_pct", "clipped above full open [%]", row->clipped_pct, "%12.3f");
  }
  table.report_to(report);
  report.print(o.json);
  return 0;
}

}  // namespace

int run_dose_command(const ExperimentOptions& o) {
  if (o.plants > 0) return run_dose_fleet_command(o);
  ex::DoseOptions options;
  options.seed = o.seed;
  const ex::DoseResult r = ex::run_dose(options);
  Report report;
  report.json()
      .add("r2", Json::number(r.r2, "%.6f"))
      .add("mean_error_pct", Json::number(r.mean_error_pct, "%.4f"));
  report.line("wheat paper dose check: 1 m/s, 0.4 MPa, 5 Hz, k = %.2f, 60 s per density",
              options.max_density);
  Table points({{"density", "density", 8, "%8.2f", "%.3f"},
                {"theoretical_l_per_min", "theory L/min", 16, "%16.4f", "%.5f"},
                {"delivered_l_per_min", "delivered L/min", 16, "%16.4f", "%.5f"},
                {"duty_pct", "duty%", 8, "%8.2f", "%.3f"}});
  for (const auto& p : r.points)
    points.row({p.density, p.theoretical_l_per_min, p.delivered_l_per_min, p.duty_pct});
  report.table(points, "points");
  report.line("R2 %.5f (paper: 0.968)  mean error %.2f %%", r.r2, r.mean_error_pct);
  report.print(o.json);

  if (!o.plot.empty()) {
    PlotSpec spec{"Delivered vs theoretical nozzle flow",
                  "theoretical flow [L/min]",
                  "delivered flow [L/min]",
                  {}};
    const auto theoretical = [](const auto& p) { return p.theoretical_l_per_min; };
    spec.series = {series_of(r.points, "y = x", kGrey, false, theoretical, theoretical),
                   series_of(r.points, "nozzle 1 (true)", kBlue, true, theoretical,
                             [](const auto& p) { return p.delivered_l_per_min; })};
    write_plot_png(spec, o.plot);
  }
  return 0;
}

}  // namespace weedspray::lab
