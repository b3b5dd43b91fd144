// SPDX-License-Identifier: Apache-2.0
// experiment step: start-up 0 -> 0.2 MPa, conventional PID against fuzzy PID (UGV Fig. 7);
// --plants: over drawn machines at several set-points with the fair search's gains.
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "lab/experiment_commands/experiment_command.hpp"
#include "lab/experiment_commands/spread_table.hpp"
#include "lab/experiments/fair_tuning.hpp"
#include "lab/report/report.hpp"

namespace weedspray::lab {
namespace {

namespace ex = lab::experiments;

void print_gains(const char* name, const control::FuzzyPidConfig& c) {
  std::fprintf(stderr, "  %-9s Kp=%.6g Ki=%.6g Kd=%.6g Cp=%.6g Ci=%.6g Cd=%.6g\n", name,
               c.base.gains.kp, c.base.gains.ki, c.base.gains.kd, c.correction_weights.kp,
               c.correction_weights.ki, c.correction_weights.kd);
}

// Per set-point over the machines; the unsettled count and the spreads lead in the JSON and
// close the text row.
Table setpoint_table() {
  return Table({{"", "controller", -10, "%-10s", ""},
                {"setpoint_mpa", "MPa", 5, "%5.2f", "%.2f"},
                {"unsettled", "", 0, "", ""},
                {"overshoot_pct", "", 0, "", ""},
                {"settle_s", "", 0, "", ""},
                {"itae", "", 0, "", ""},
                {"", "overshoot% mean/max", 17, "%8.2f", ""},
                {"", "", 0, "%8.2f", ""},
                {"", "settle_s mean/max", 17, "%8.3f", ""},
                {"", "", 0, "%8.3f", ""},
                {"", "ITAE mean/max", 21, "%10.6f", ""},
                {"", "", 0, "%10.6f", ""},
                {"", "unsettled", 9, "%9d", ""}});
}

std::vector<Cell> setpoint_cells(const char* controller, const ex::StepFleetRow& row) {
  return {std::string(controller),
          row.setpoint_mpa,
          static_cast<long long>(row.unsettled),
          spread_json(row.overshoot_pct),
          spread_json(row.settle_s),
          spread_json(row.itae),
          row.overshoot_pct.mean,
          row.overshoot_pct.worst,
          row.settle_s.mean,
          row.settle_s.worst,
          row.itae.mean,
          row.itae.worst,
          static_cast<long long>(row.unsettled)};
}

Json gains_json(const control::FuzzyPidConfig& g) {
  Json out = Json::object();
  const char* keys[] = {"kp", "ki", "kd", "cp", "ci", "cd"};
  const double values[] = {g.base.gains.kp,         g.base.gains.ki,
                           g.base.gains.kd,         g.correction_weights.kp,
                           g.correction_weights.ki, g.correction_weights.kd};
  for (int i = 0; i < 6; ++i) out.add(keys[i], Json::number(values[i], "%.5g"));
  return out;
}

int run_step_fleet_command(const ExperimentOptions& o) {
  control::FuzzyPidConfig pid = ex::fair_tuned_pid_config();
  control::FuzzyPidConfig fuzzy = ex::fair_tuned_fuzzy_pid_config();
  // Another loop than the daemon's default (e.g. a slower pressure.loop_hz over a Modbus ADC).
  ex::StepOptions timing = ex::daemon_step_timing();
  if (o.control_period_ms) timing.control_period_s = *o.control_period_ms / 1e3;
  if (o.converter_lead_ms) timing.converter_lead_s = *o.converter_lead_ms / 1e3;
  if (o.converter_lag_ms) timing.converter_lag_s = *o.converter_lag_ms / 1e3;
  if (o.tune) {
    const auto t0 = std::chrono::steady_clock::now();
    const ex::FairTuningResult t =
        ex::tune_fair(ex::training_set(o.seed, 5, timing), o.tune_budget);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr,
                 "fair tuning (compass search, %d + %d evaluations, %.1f s): training ITAE PID "
                 "%.6f%s, fuzzy PID %.6f%s\n",
                 t.pid.evaluations, t.fuzzy_pid.evaluations, wall, t.pid.training_itae,
                 t.pid.on_bound ? " (ON A BOUND)" : "", t.fuzzy_pid.training_itae,
                 t.fuzzy_pid.on_bound ? " (ON A BOUND)" : "");
    pid = t.pid.config;
    fuzzy = t.fuzzy_pid.config;
  }
  print_gains("PID", pid);
  print_gains("fuzzy PID", fuzzy);
  const ex::StepFleetResult r =
      ex::run_step_fleet({o.seed, o.plants, false}, pid, fuzzy, {0.2, 0.4}, timing);

  Report report = fleet_report(o.plants, o.seed);
  report.json()
      .add("control_period_s", Json::number(timing.control_period_s, "%g"))
      .add("converter_lead_s", Json::number(timing.converter_lead_s, "%g"))
      .add("converter_lag_s", Json::number(timing.converter_lag_s, "%g"));
  report.line(
      "start-up with 4 nozzles open on %d held-out machines (seed %llu), the loop: %g Hz, "
      "ADC %g ms before / DAC %g ms after each tick; gains from the fair search%s",
      o.plants, static_cast<unsigned long long>(o.seed), 1.0 / timing.control_period_s,
      timing.converter_lead_s * 1e3, timing.converter_lag_s * 1e3,
      o.tune ? " (rerun with this loop)" : "");
  // The text interleaves the controllers per set-point; the JSON lists each one's set-points.
  Table both = setpoint_table();
  for (std::size_t i = 0; i < r.pid.rows.size(); ++i) {
    both.row(setpoint_cells("PID", r.pid.rows[i]));
    both.row(setpoint_cells("fuzzy PID", r.fuzzy_pid.rows[i]));
  }
  report.lines(both.text_lines());
  for (const auto& [key, controller, gains] :
       {std::tuple{"pid", &r.pid, &pid}, std::tuple{"fuzzy_pid", &r.fuzzy_pid, &fuzzy}}) {
    Table setpoints = setpoint_table();
    for (const auto& row : controller->rows) setpoints.row(setpoint_cells("", row));
    report.json().add(
        key, gains_json(*gains)
                 .add("operating_points_itae", spread_json(controller->operating_points_itae))
                 .add("setpoints", setpoints.json()));
  }
  report.line(
      "mean ITAE over 0.2-0.5 MPa x 1-4 nozzles, per machine: PID %.6f (sd %.6f, worst "
      "%.6f), fuzzy PID %.6f (sd %.6f, worst %.6f)",
      r.pid.operating_points_itae.mean, r.pid.operating_points_itae.sd,
      r.pid.operating_points_itae.worst, r.fuzzy_pid.operating_points_itae.mean,
      r.fuzzy_pid.operating_points_itae.sd, r.fuzzy_pid.operating_points_itae.worst);
  report.print(o.json);
  return 0;
}

// One machine's start-up per controller: a text row and a JSON object ("pid", "fuzzy_pid").
Table startup_table() {
  return Table({{"", "controller", -10, "%-10s", ""},
                {"rise_s", "rise_s", 8, "%8.3f", "%.4f"},
                {"overshoot_pct", "overshoot%", 10, "%10.2f", "%.3f"},
                {"settle_s", "settle_s", 9, "%9.3f", "%.4f"},
                {"itae", "ITAE", 10, "%10.5f", "%.6f"},
                {"settled", "", 0, "", ""},
                {"kp", "gains", 0, "Kp=%.4g", "%.4g", "   "},
                {"ki", "", 0, "Ki=%.4g", "%.4g"},
                {"kd", "", 0, "Kd=%.4g", "%.4g"},
                {"cp", "", 0, "", "%.4g"},
                {"ci", "", 0, "", "%.4g"},
                {"cd", "", 0, "", "%.4g"}});
}

std::vector<Cell> startup_cells(const char* controller, const ex::StepRun& run,
                                const control::PidGains* weights) {
  const ex::StepMetrics& m = run.metrics;
  const control::PidGains w = weights ? *weights : control::PidGains{};
  std::vector<Cell> cells{std::string(controller),
                          m.rise_s,
                          m.overshoot_pct,
                          m.settle_s,
                          m.itae,
                          m.settled,
                          run.gains.kp,
                          run.gains.ki,
                          run.gains.kd,
                          w.kp,
                          w.ki,
                          w.kd};
  // The conventional PID has no correction weights.
  if (!weights) std::fill(cells.end() - 3, cells.end(), Cell{});
  return cells;
}

}  // namespace

int run_step_command(const ExperimentOptions& o) {
  if (o.plants > 0) return run_step_fleet_command(o);
  ex::StepOptions options;
  options.seed = o.seed;
  options.control_period_s = o.control_period_ms.value_or(5.0) / 1e3;
  options.converter_lead_s = o.converter_lead_ms.value_or(0.0) / 1e3;
  options.converter_lag_s = o.converter_lag_ms.value_or(0.0) / 1e3;
  if (o.tune) {
    const auto t0 = std::chrono::steady_clock::now();
    const ex::TuningResult t = ex::tune_step_controllers(options);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr,
                 "tuning: %d candidates in %.1f s\n  PID       Kp=%.4g Ki=%.4g Kd=%.4g  ITAE %.5f\n"
                 "  fuzzy PID Kp'=%.4g Ki'=%.4g Kd'=%.4g Cp=%.4g Ci=%.4g Cd=%.4g  ITAE %.5f\n",
                 t.candidates_evaluated, wall, t.pid.kp, t.pid.ki, t.pid.kd, t.pid_metrics.itae,
                 t.fuzzy.base.gains.kp, t.fuzzy.base.gains.ki, t.fuzzy.base.gains.kd,
                 t.fuzzy.correction_weights.kp, t.fuzzy.correction_weights.ki,
                 t.fuzzy.correction_weights.kd, t.fuzzy_metrics.itae);
    options.pid_gains = t.pid;
    options.fuzzy = t.fuzzy;
  }
  const ex::StepResult r = ex::run_step(options);

  Report report;
  report.line("start-up 0 -> %.2f MPa, 4 nozzles open (UGV Fig. 7)", r.setpoint_mpa);
  Table startup = startup_table();
  startup.row("pid", startup_cells("PID", r.pid, nullptr));
  startup.row("fuzzy_pid", startup_cells("fuzzy PID", r.fuzzy_pid, &r.fuzzy_correction_weights));
  report.table(startup);
  report.line("fuzzy correction weights Cp=%.4g Ci=%.4g Cd=%.4g; settle band +-2 %%",
              r.fuzzy_correction_weights.kp, r.fuzzy_correction_weights.ki,
              r.fuzzy_correction_weights.kd);
  report.json().add("setpoint_mpa", Json::number(r.setpoint_mpa, "%.3f"));
  report.print(o.json);

  if (!o.plot.empty()) {
    PlotSpec spec{"Start-up to 0.2 MPa: conventional PID vs fuzzy PID",
                  "time [s]",
                  "line pressure [MPa]",
                  {}};
    spec.series.push_back(pressure_series(r.pid.trace, "conventional PID", kBlue));
    spec.series.push_back(pressure_series(r.fuzzy_pid.trace, "fuzzy PID", kRed));
    spec.series.push_back({"set-point", {0.0, 3.0}, {r.setpoint_mpa, r.setpoint_mpa}, kGrey});
    write_plot_png(spec, o.plot);
  }
  return 0;
}

}  // namespace weedspray::lab
