// SPDX-License-Identifier: Apache-2.0
// experiment ripple: line pressure ripple with the nozzles' PWM in phase against staggered
// (UGV Fig. 8); --plants: over drawn machines, at the manifold and along the boom.
#include <vector>

#include "lab/experiment_commands/experiment_command.hpp"
#include "lab/experiment_commands/spread_table.hpp"
#include "lab/report/report.hpp"

namespace weedspray::lab {
namespace {

namespace ex = lab::experiments;

int run_ripple_fleet_command(const ExperimentOptions& o) {
  ex::FleetOptions fleet{o.seed, o.plants, false};
  const ex::RippleOptions options;
  const ex::RippleFleetResult r = ex::run_ripple_fleet(fleet, options);
  Report report = fleet_report(o.plants, o.seed);
  report.line(
      "4 nozzles at %.0f %% duty, %.0f Hz, fuzzy PID at 0.2 MPa, %d drawn machines (seed %llu): "
      "pump pulsation, hose inertia, valve spreads on",
      options.duty_pct, options.frequency_hz, o.plants, static_cast<unsigned long long>(o.seed));
  report.json()
      .add("synchronous_pp_mpa", spread_json(r.synchronous_pp_mpa))
      .add("staggered_pp_mpa", spread_json(r.staggered_pp_mpa))
      .add("ratio", spread_json(r.ratio))
      .add("synchronous_boom_pp_mpa", spread_json(r.synchronous_boom_pp_mpa))
      .add("staggered_boom_pp_mpa", spread_json(r.staggered_boom_pp_mpa))
      .add("duty_pct", Json::number(options.duty_pct, "%.0f"))
      .add("frequency_hz", Json::number(options.frequency_hz, "%.1f"));
  // Text only: the JSON above keeps its own order.
  SpreadTable("pressure p-p [MPa]")
      .row("", "synchronous, manifold (sensor)", r.synchronous_pp_mpa, "%12.5f")
      .row("", "staggered, manifold (sensor)", r.staggered_pp_mpa, "%12.5f")
      .row("", "synchronous, boom", r.synchronous_boom_pp_mpa, "%12.5f")
      .row("", "staggered, boom", r.staggered_boom_pp_mpa, "%12.5f")
      .row("", "ratio sync/stag (worst = lowest)", r.ratio, "%12.2f")
      .report_to(report);
  report.print(o.json);
  return 0;
}

}  // namespace

int run_ripple_command(const ExperimentOptions& o) {
  if (o.plants > 0) return run_ripple_fleet_command(o);
  ex::RippleOptions options;
  options.seed = o.seed;
  const ex::RippleResult r = ex::run_ripple(options);
  const double ratio = r.staggered.pp_mpa > 0 ? r.synchronous.pp_mpa / r.staggered.pp_mpa : 0.0;
  Report report;
  report.line("4 nozzles at %.0f %% duty, %.0f Hz, fuzzy PID at 0.2 MPa (UGV Fig. 8)",
              options.duty_pct, options.frequency_hz);
  Table pwm({{"", "PWM", -12, "%-12s", ""}, {"", "pressure p-p [MPa]", 18, "%18.5f", ""}});
  pwm.row({std::string("synchronous"), r.synchronous.pp_mpa});
  pwm.row({std::string("staggered"), r.staggered.pp_mpa});
  report.table(pwm);
  report.line("synchronous / staggered = %.1f x", ratio);
  report.json()
      .add("synchronous_pp_mpa", Json::number(r.synchronous.pp_mpa, "%.5f"))
      .add("staggered_pp_mpa", Json::number(r.staggered.pp_mpa, "%.5f"))
      .add("ratio", Json::number(ratio, "%.2f"))
      .add("duty_pct", Json::number(options.duty_pct, "%.0f"))
      .add("frequency_hz", Json::number(options.frequency_hz, "%.1f"));
  report.print(o.json);

  if (!o.plot.empty()) {
    PlotSpec spec{"Line pressure, 4 nozzles at 50 % / 3 Hz", "time [s]", "line pressure [MPa]", {}};
    const double t0 = r.synchronous.trace.empty() ? 0.0 : r.synchronous.trace.front().time_s;
    auto first_two_seconds = [&](const std::vector<ex::TraceSample>& trace) {
      std::vector<ex::TraceSample> out;
      for (const auto& s : trace)
        if (s.time_s - t0 <= 2.0) out.push_back(s);
      return out;
    };
    spec.series.push_back(
        pressure_series(first_two_seconds(r.synchronous.trace), "synchronous", kBlue, t0));
    spec.series.push_back(
        pressure_series(first_two_seconds(r.staggered.trace), "staggered T/4", kRed, t0));
    write_plot_png(spec, o.plot);
  }
  return 0;
}

}  // namespace weedspray::lab
