// SPDX-License-Identifier: Apache-2.0
// experiment orthogonal: the L16 orthogonal test, four nozzles at mixed duties per run;
// --plants: over drawn machines, calibrated as made, then changed (--change-parts).
#include <string>
#include <tuple>

#include "lab/experiment_commands/duty_points.hpp"
#include "lab/experiment_commands/experiment_command.hpp"
#include "lab/experiment_commands/spread_table.hpp"
#include "lab/report/report.hpp"

namespace weedspray::lab {
namespace {

namespace ex = lab::experiments;

ex::ChangeParts change_parts(const std::string& name) {
  if (name == "common") return ex::ChangeParts::kCommon;
  if (name == "nozzle") return ex::ChangeParts::kPerNozzle;
  if (name == "none") return ex::ChangeParts::kNone;
  return ex::ChangeParts::kAll;
}

int run_orthogonal_fleet_command(const ExperimentOptions& o) {
  ex::FleetOptions fleet{o.seed, o.plants, true};
  fleet.parts = change_parts(o.change_parts);
  const ex::SprayRunOptions base;
  const ex::OrthogonalFleetResult r = ex::run_orthogonal_fleet(fleet, base);
  Report report = fleet_report(o.plants, o.seed);
  report.json()
      .add("changed_after_calibration", Json::boolean(fleet.parts != ex::ChangeParts::kNone))
      .add("change_parts", Json::string(o.change_parts))
      .add("target_follows_speed", Json::boolean(base.follow_speed))
      .add("reference_speed_m_per_s", Json::number(base.reference_speed_m_per_s, "%.3g"))
      .add("speed_m_per_s", Json::object()
                                .add("min", Json::number(r.speed_min_m_per_s, "%.4g"))
                                .add("max", Json::number(r.speed_max_m_per_s, "%.4g")));
  report.line(
      "L16 orthogonal test, 0.2 MPa, 3 Hz, %d drawn machines (seed %llu), each calibrated as "
      "made, then changed (%s of: wear, a partial blockage, valve ageing, meter drift, supply "
      "and speed ramps)",
      o.plants, static_cast<unsigned long long>(o.seed), o.change_parts.c_str());
  report.line(
      "the duties are the demand at %.1f m/s; %s (speeds %.2f-%.2f m/s), clipped at the "
      "full-open flow",
      base.reference_speed_m_per_s,
      base.follow_speed ? "the target follows the ground speed" : "the target ignores the speed",
      r.speed_min_m_per_s, r.speed_max_m_per_s);
  SpreadTable table("over the machines");
  for (const auto& [key, name, row] :
       {std::tuple{"trim_on", "ON (the daemon's: ratio, FlowTrim)", &r.trim_on},
        std::tuple{"model_trim", "ON: model (BoomTrim, lab only)", &r.model_trim},
        std::tuple{"trim_off", "OFF", &r.trim_off},
        std::tuple{"recalibrated", "ON (the daemon's), recalibrated after the change",
                   &r.recalibrated},
        std::tuple{"headland_recheck",
                   "ON (the daemon's), each nozzle re-checked alone at a headland after the change",
                   &r.headland_recheck}}) {
    table.section(key, std::string("online flow trim ") + name)
        .row("mean_error_pct", "mean error [%]", row->mean_error_pct, "%12.3f")
        .row("max_error_pct", "max error [%]", row->max_error_pct, "%12.3f")
        .row("max_error_below_100_pct", "  ...below 100 % duty [%]", row->max_error_modulated_pct,
             "%12.3f")
        .row("pressure_band_mpa", "pressure band [MPa]", row->pressure_band_mpa, "%12.4f")
        .row("clipped_pct", "clipped above full open [%]", row->clipped_pct, "%12.3f")
        .member("per_nozzle_error_pct",
                Json::object()
                    .add("mean", Json::number(row->per_nozzle_mean_error_pct, "%.6g"))
                    .add("p95", Json::number(row->per_nozzle_p95_error_pct, "%.6g")),
                format_text("%-34s%12.3f   p95 %.3f", "every nozzle-run: mean error [%]",
                            row->per_nozzle_mean_error_pct, row->per_nozzle_p95_error_pct));
  }
  // Text only below: their JSON follows in its own order.
  table.section("", "floor of any controller holding 100 % open at one pressure (plant truth)")
      .row("", "max error [%]", r.held_open_floor_pct, "%12.3f")
      .section("",
               "floor of any boom-wide law (one factor for the modulated nozzles, the pressure "
               "for the held-open ones; plant truth)")
      .row("", "mean error [%]", r.common_floor_pct, "%12.3f")
      .section("",
               "each nozzle's ratio as one line meter tells it (phase-window fit over each run, "
               "trim ON; nozzle-runs below 100 % duty): error against the truth")
      .row("", "mean error [%]", r.trim_on.mean_identification_error_pct, "%12.3f")
      .row("", "max error [%]", r.trim_on.max_identification_error_pct, "%12.3f")
      .report_to(report);
  report.json()
      .add("nozzle_identification_error_pct",
           Json::object()
               .add("mean", spread_json(r.trim_on.mean_identification_error_pct))
               .add("max", spread_json(r.trim_on.max_identification_error_pct)))
      .add("common_floor_mean_error_pct", spread_json(r.common_floor_pct))
      .add("held_open_floor_pct", spread_json(r.held_open_floor_pct));
  report.print(o.json);
  return 0;
}

// One L16 run: the text shows the four duties and errors, the JSON each nozzle's duty point.
Table run_table() {
  return Table({{"run", "run", 4, "%4zu", ""},
                {"pressure_band_mpa", "", 0, "", "%.5f"},
                {"nozzles", "", 0, "", ""},
                {"", "duty A B C D [%]", 23, "%5.0f", ""},
                {"", "", 0, "%5.0f", ""},
                {"", "", 0, "%5.0f", ""},
                {"", "", 0, "%5.0f", ""},
                {"", "error A B C D [%]", 31, "%7.2f", "", "   "},
                {"", "", 0, "%7.2f", ""},
                {"", "", 0, "%7.2f", ""},
                {"", "", 0, "%7.2f", ""},
                {"", "band MPa", 10, "%10.4f", ""}});
}

}  // namespace

int run_orthogonal_command(const ExperimentOptions& o) {
  if (o.plants > 0) return run_orthogonal_fleet_command(o);
  ex::SprayRunOptions options;
  options.seed = o.seed;
  options.raw = o.raw;
  const ex::OrthogonalResult r = ex::run_orthogonal(options);
  Report report;
  report.json()
      .add("raw", Json::boolean(r.raw))
      .add("mean_error_pct", Json::number(r.mean_error_pct, "%.4f"))
      .add("max_error_pct", Json::number(r.max_error_pct, "%.4f"))
      .add("pressure_band_mpa", Json::number(r.pressure_band_mpa, "%.5f"));
  report.line("L16 orthogonal test, 0.2 MPa, 3 Hz, 30 s per run (%s)", spray_run_mode(r.raw));
  Table runs = run_table();
  for (std::size_t i = 0; i < r.runs.size(); ++i) {
    const auto& n = r.runs[i].nozzles;
    Table nozzles = duty_point_table();
    for (std::size_t k = 0; k < 4; ++k) nozzles.row(duty_point_cells(n[k]));
    runs.row({static_cast<long long>(i + 1), r.runs[i].pressure_band_mpa, nozzles.json(),
              n[0].duty_pct, n[1].duty_pct, n[2].duty_pct, n[3].duty_pct, n[0].error_pct,
              n[1].error_pct, n[2].error_pct, n[3].error_pct, r.runs[i].pressure_band_mpa});
  }
  report.table(runs, "runs");
  report.line("mean error %.2f %%  max error %.2f %%  pressure band %.4f MPa", r.mean_error_pct,
              r.max_error_pct, r.pressure_band_mpa);
  report.print(o.json);

  if (!o.plot.empty()) {
    PlotSpec spec{
        "L16 orthogonal test: volume error per nozzle and duty", "duty [%]", "error [%]", {}};
    const int colours[] = {kBlue, kOrange, kGreen, kRed};
    for (std::size_t k = 0; k < 4; ++k) {
      PlotSeries s{std::string("nozzle ") + char('A' + k), {}, {}, colours[k], true};
      for (const auto& run : r.runs) {
        s.x.push_back(run.nozzles[k].duty_pct + (static_cast<double>(k) - 1.5));
        s.y.push_back(run.nozzles[k].error_pct);
      }
      spec.series.push_back(s);
    }
    write_plot_png(spec, o.plot);
  }
  return 0;
}

}  // namespace weedspray::lab
