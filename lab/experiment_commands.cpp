// weedspray-lab experiment NAME [--json] [--plot OUT.png] [--raw] [--seed N] [--tune]
// Reruns the papers' experiments on the simulated machine (lab/experiments/).
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "lab/commands.hpp"
#include "lab/experiment_field.hpp"
#include "lab/experiment_plot.hpp"
#include "lab/experiments/experiments.hpp"
#include "lab/experiments/fair_tuning.hpp"
#include "lab/vision_dataset.hpp"
#include "lab/weed_eval_command.hpp"
#include "lab/weed_model.hpp"

namespace weedspray::lab {
namespace {

namespace ex = lab::experiments;

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
  double decision_threshold = -1.0;    // < 0: the daemon's spray.decision_threshold default
  std::string health_judge = "cusum";  // blockage: NozzleHealth's judge (band | cusum)
  std::string change_parts = "all";    // orthogonal --plants: which part of the change
  // step: the pressure loop's timing; unset: 5 / 0 / 0 ms for one machine, the daemon's
  // (10 / 2.5 / 1 ms) for --plants.
  std::optional<double> control_period_ms;
  std::optional<double> converter_lead_ms;
  std::optional<double> converter_lag_ms;
};

constexpr int kBlue = 0x1f77b4, kOrange = 0xff7f0e, kGreen = 0x2ca02c, kRed = 0xd62728,
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

PlotSeries pressure_series(const std::vector<ex::TraceSample>& trace, const std::string& name,
                           int rgb, double t_offset = 0.0) {
  PlotSeries s{name, {}, {}, rgb, false};
  for (const auto& p : trace) {
    s.x.push_back(p.time_s - t_offset);
    s.y.push_back(p.pressure_mpa);
  }
  return s;
}

void print_metrics_json(const char* key, const ex::StepRun& run, const control::PidGains* weights,
                        bool comma) {
  std::printf(
      "\"%s\": {\"rise_s\": %.4f, \"overshoot_pct\": %.3f, \"settle_s\": %.4f, \"itae\": %.6f, "
      "\"settled\": %s, \"kp\": %.4g, \"ki\": %.4g, \"kd\": %.4g",
      key, run.metrics.rise_s, run.metrics.overshoot_pct, run.metrics.settle_s, run.metrics.itae,
      run.metrics.settled ? "true" : "false", run.gains.kp, run.gains.ki, run.gains.kd);
  if (weights)
    std::printf(", \"cp\": %.4g, \"ci\": %.4g, \"cd\": %.4g", weights->kp, weights->ki,
                weights->kd);
  std::printf("}%s", comma ? ", " : "");
}

void print_spread_json(const char* key, const ex::Spread& s, bool comma = true) {
  std::printf("\"%s\": {\"mean\": %.6g, \"sd\": %.6g, \"worst\": %.6g, \"n\": %d}%s", key, s.mean,
              s.sd, s.worst, s.count, comma ? ", " : "");
}

// One object of named spreads: "key": {"a": {...}, "b": {...}}.
void print_spreads_json(const char* key,
                        std::initializer_list<std::pair<const char*, const ex::Spread*>> spreads,
                        bool comma) {
  std::printf("\"%s\": {", key);
  std::size_t i = 0;
  for (const auto& [name, spread] : spreads) print_spread_json(name, *spread, ++i < spreads.size());
  std::printf("}%s", comma ? ", " : "");
}

void print_spread_row(const char* name, const ex::Spread& s, const char* format) {
  std::printf("%-34s", name);
  for (double v : {s.mean, s.sd, s.worst}) std::printf(format, v);
  std::printf("\n");
}

void print_gains(const char* name, const control::FuzzyPidConfig& c) {
  std::fprintf(stderr, "  %-9s Kp=%.6g Ki=%.6g Kd=%.6g Cp=%.6g Ci=%.6g Cd=%.6g\n", name,
               c.base.gains.kp, c.base.gains.ki, c.base.gains.kd, c.correction_weights.kp,
               c.correction_weights.ki, c.correction_weights.kd);
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
  if (o.json) {
    std::printf(
        "{\"plants\": %d, \"seed\": %llu, \"control_period_s\": %g, "
        "\"converter_lead_s\": %g, \"converter_lag_s\": %g, ",
        o.plants, static_cast<unsigned long long>(o.seed), timing.control_period_s,
        timing.converter_lead_s, timing.converter_lag_s);
    for (const auto* c : {&r.pid, &r.fuzzy_pid}) {
      const bool is_pid = c == &r.pid;
      const auto& g = is_pid ? pid : fuzzy;
      std::printf(
          "\"%s\": {\"kp\": %.5g, \"ki\": %.5g, \"kd\": %.5g, \"cp\": %.5g, "
          "\"ci\": %.5g, \"cd\": %.5g, ",
          is_pid ? "pid" : "fuzzy_pid", g.base.gains.kp, g.base.gains.ki, g.base.gains.kd,
          g.correction_weights.kp, g.correction_weights.ki, g.correction_weights.kd);
      print_spread_json("operating_points_itae", c->operating_points_itae);
      std::printf("\"setpoints\": [");
      for (std::size_t i = 0; i < c->rows.size(); ++i) {
        const auto& row = c->rows[i];
        std::printf("%s{\"setpoint_mpa\": %.2f, \"unsettled\": %d, ", i ? ", " : "",
                    row.setpoint_mpa, row.unsettled);
        print_spread_json("overshoot_pct", row.overshoot_pct);
        print_spread_json("settle_s", row.settle_s);
        print_spread_json("itae", row.itae, false);
        std::printf("}");
      }
      std::printf("]}%s", is_pid ? ", " : "");
    }
    std::printf("}\n");
  } else {
    std::printf(
        "start-up with 4 nozzles open on %d held-out machines (seed %llu), the loop: %g Hz, "
        "ADC %g ms before / DAC %g ms after each tick; gains from the fair search%s\n",
        o.plants, static_cast<unsigned long long>(o.seed), 1.0 / timing.control_period_s,
        timing.converter_lead_s * 1e3, timing.converter_lag_s * 1e3,
        o.tune ? " (rerun with this loop)" : "");
    std::printf("%-10s %5s %17s %17s %21s %9s\n", "controller", "MPa", "overshoot% mean/max",
                "settle_s mean/max", "ITAE mean/max", "unsettled");
    for (std::size_t i = 0; i < r.pid.rows.size(); ++i)
      for (const auto* c : {&r.pid, &r.fuzzy_pid}) {
        const auto& row = c->rows[i];
        std::printf("%-10s %5.2f %8.2f %8.2f %8.3f %8.3f %10.6f %10.6f %9d\n",
                    c == &r.pid ? "PID" : "fuzzy PID", row.setpoint_mpa, row.overshoot_pct.mean,
                    row.overshoot_pct.worst, row.settle_s.mean, row.settle_s.worst, row.itae.mean,
                    row.itae.worst, row.unsettled);
      }
    std::printf(
        "mean ITAE over 0.2-0.5 MPa x 1-4 nozzles, per machine: PID %.6f (sd %.6f, worst "
        "%.6f), fuzzy PID %.6f (sd %.6f, worst %.6f)\n",
        r.pid.operating_points_itae.mean, r.pid.operating_points_itae.sd,
        r.pid.operating_points_itae.worst, r.fuzzy_pid.operating_points_itae.mean,
        r.fuzzy_pid.operating_points_itae.sd, r.fuzzy_pid.operating_points_itae.worst);
  }
  return 0;
}

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
  if (o.json) {
    std::printf("{");
    print_metrics_json("pid", r.pid, nullptr, true);
    print_metrics_json("fuzzy_pid", r.fuzzy_pid, &r.fuzzy_correction_weights, false);
    std::printf(", \"setpoint_mpa\": %.3f}\n", r.setpoint_mpa);
  } else {
    std::printf("start-up 0 -> %.2f MPa, 4 nozzles open (UGV Fig. 7)\n", r.setpoint_mpa);
    std::printf("%-10s %8s %10s %9s %10s   gains\n", "controller", "rise_s", "overshoot%",
                "settle_s", "ITAE");
    for (const auto* run : {&r.pid, &r.fuzzy_pid})
      std::printf("%-10s %8.3f %10.2f %9.3f %10.5f   Kp=%.4g Ki=%.4g Kd=%.4g\n",
                  run == &r.pid ? "PID" : "fuzzy PID", run->metrics.rise_s,
                  run->metrics.overshoot_pct, run->metrics.settle_s, run->metrics.itae,
                  run->gains.kp, run->gains.ki, run->gains.kd);
    std::printf("fuzzy correction weights Cp=%.4g Ci=%.4g Cd=%.4g; settle band +-2 %%\n",
                r.fuzzy_correction_weights.kp, r.fuzzy_correction_weights.ki,
                r.fuzzy_correction_weights.kd);
  }
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

int run_ripple_fleet_command(const ExperimentOptions& o) {
  ex::FleetOptions fleet{o.seed, o.plants, false};
  const ex::RippleOptions options;
  const ex::RippleFleetResult r = ex::run_ripple_fleet(fleet, options);
  if (o.json) {
    std::printf("{\"plants\": %d, \"seed\": %llu, ", o.plants,
                static_cast<unsigned long long>(o.seed));
    print_spread_json("synchronous_pp_mpa", r.synchronous_pp_mpa);
    print_spread_json("staggered_pp_mpa", r.staggered_pp_mpa);
    print_spread_json("ratio", r.ratio);
    print_spread_json("synchronous_boom_pp_mpa", r.synchronous_boom_pp_mpa);
    print_spread_json("staggered_boom_pp_mpa", r.staggered_boom_pp_mpa);
    std::printf("\"duty_pct\": %.0f, \"frequency_hz\": %.1f}\n", options.duty_pct,
                options.frequency_hz);
  } else {
    std::printf(
        "4 nozzles at %.0f %% duty, %.0f Hz, fuzzy PID at 0.2 MPa, %d drawn machines (seed %llu): "
        "pump pulsation, hose inertia, valve spreads on\n",
        options.duty_pct, options.frequency_hz, o.plants, static_cast<unsigned long long>(o.seed));
    std::printf("%-34s%12s%12s%12s\n", "pressure p-p [MPa]", "mean", "sd", "worst");
    print_spread_row("synchronous, manifold (sensor)", r.synchronous_pp_mpa, "%12.5f");
    print_spread_row("staggered, manifold (sensor)", r.staggered_pp_mpa, "%12.5f");
    print_spread_row("synchronous, boom", r.synchronous_boom_pp_mpa, "%12.5f");
    print_spread_row("staggered, boom", r.staggered_boom_pp_mpa, "%12.5f");
    print_spread_row("ratio sync/stag (worst = lowest)", r.ratio, "%12.2f");
  }
  return 0;
}

ex::ChangeParts change_parts(const std::string& name) {
  if (name == "common") return ex::ChangeParts::kCommon;
  if (name == "nozzle") return ex::ChangeParts::kPerNozzle;
  if (name == "none") return ex::ChangeParts::kNone;
  return ex::ChangeParts::kAll;
}

int run_orthogonal_fleet_command(const ExperimentOptions& o) {
  ex::FleetOptions fleet{o.seed, o.plants, true};
  fleet.parts = change_parts(o.change_parts);
  const ex::OrthogonalFleetResult r = ex::run_orthogonal_fleet(fleet);
  const std::array rows{
      std::tuple{"trim_on", "ON (the daemon's: ratio, FlowTrim)", &r.trim_on},
      std::tuple{"model_trim", "ON: model (BoomTrim, lab only)", &r.model_trim},
      std::tuple{"trim_off", "OFF", &r.trim_off},
      std::tuple{"recalibrated", "ON (the daemon's), recalibrated after the change",
                 &r.recalibrated}};
  if (o.json) {
    std::printf(
        "{\"plants\": %d, \"seed\": %llu, \"changed_after_calibration\": %s, "
        "\"change_parts\": \"%s\", ",
        o.plants, static_cast<unsigned long long>(o.seed),
        fleet.parts == ex::ChangeParts::kNone ? "false" : "true", o.change_parts.c_str());
    for (const auto& [key, name, row] : rows)
      print_spreads_json(key,
                         {{"mean_error_pct", &row->mean_error_pct},
                          {"max_error_pct", &row->max_error_pct},
                          {"max_error_below_100_pct", &row->max_error_modulated_pct},
                          {"pressure_band_mpa", &row->pressure_band_mpa}},
                         true);
    print_spreads_json("nozzle_identification_error_pct",
                       {{"mean", &r.trim_on.mean_identification_error_pct},
                        {"max", &r.trim_on.max_identification_error_pct}},
                       true);
    print_spread_json("common_floor_mean_error_pct", r.common_floor_pct);
    print_spread_json("held_open_floor_pct", r.held_open_floor_pct, false);
    std::printf("}\n");
  } else {
    std::printf(
        "L16 orthogonal test, 0.2 MPa, 3 Hz, %d drawn machines (seed %llu), each calibrated as "
        "made, then changed (%s of: wear, a partial blockage, valve ageing, meter drift, supply "
        "and speed ramps)\n",
        o.plants, static_cast<unsigned long long>(o.seed), o.change_parts.c_str());
    std::printf("%-34s%12s%12s%12s\n", "over the machines", "mean", "sd", "worst");
    for (const auto& [key, name, row] : rows) {
      std::printf("-- online flow trim %s\n", name);
      print_spread_row("mean error [%]", row->mean_error_pct, "%12.3f");
      print_spread_row("max error [%]", row->max_error_pct, "%12.3f");
      print_spread_row("  ...below 100 % duty [%]", row->max_error_modulated_pct, "%12.3f");
      print_spread_row("pressure band [MPa]", row->pressure_band_mpa, "%12.4f");
    }
    std::printf("-- floor of any controller holding 100 %% open at one pressure (plant truth)\n");
    print_spread_row("max error [%]", r.held_open_floor_pct, "%12.3f");
    std::printf(
        "-- floor of any boom-wide law (one factor for the modulated nozzles, the pressure for "
        "the held-open ones; plant truth)\n");
    print_spread_row("mean error [%]", r.common_floor_pct, "%12.3f");
    std::printf(
        "-- each nozzle's ratio as one line meter tells it (phase-window fit over each run, "
        "trim ON; nozzle-runs below 100 %% duty): error against the truth\n");
    print_spread_row("mean error [%]", r.trim_on.mean_identification_error_pct, "%12.3f");
    print_spread_row("max error [%]", r.trim_on.max_identification_error_pct, "%12.3f");
  }
  return 0;
}

int run_blockage_command(const ExperimentOptions& o) {
  const ex::FleetOptions fleet{o.seed, o.plants > 0 ? o.plants : 20, false};
  ex::BlockageOptions options;
  options.health.judge =
      o.health_judge == "band" ? control::NozzleJudge::kBand : control::NozzleJudge::kCusum;
  const ex::BlockageFleetResult r = ex::run_blockage_fleet(fleet, options);
  if (o.json) {
    std::printf(
        "{\"judge\": \"%s\", \"plants\": %d, \"seed\": %llu, \"blockage\": %.2f, "
        "\"limit_s\": %.1f, "
        "\"named_within_limit\": %d, \"false_alarms\": %d, \"healthy_minutes\": %.1f, ",
        o.health_judge.c_str(), fleet.plants, static_cast<unsigned long long>(o.seed),
        options.blockage, options.detect_limit_s, r.named_within_limit, r.false_alarms,
        r.healthy_minutes);
    print_spread_json("detect_s", r.detect_s);
    print_spread_json("healthy_worst_deviation", r.healthy_worst_deviation);
    print_spread_json("healthy_max_evidence", r.healthy_max_evidence);
    std::printf("\"machines\": [");
    for (std::size_t i = 0; i < r.machines.size(); ++i) {
      const auto& m = r.machines[i];
      std::printf(
          "%s{\"blocked\": %d, \"named\": %d, \"detect_s\": %.2f, "
          "\"false_alarm\": %s, \"healthy_worst_deviation\": %.3f, "
          "\"healthy_max_evidence\": %.2f}",
          i ? ", " : "", m.blocked_nozzle + 1, m.named_nozzle + 1, m.detect_s,
          m.false_alarm ? "true" : "false", m.healthy_worst_deviation, m.healthy_max_evidence);
    }
    std::printf("]}\n");
  } else {
    std::printf(
        "per-nozzle health from the line meter (%s judge), %d drawn machines (seed %llu), "
        "variable-rate "
        "spraying at %.1f MPa / %.0f Hz, staggered, trim on: %.0f s baseline + %.0f min healthy, "
        "then one nozzle %.0f %% blocked\n",
        o.health_judge.c_str(), fleet.plants, static_cast<unsigned long long>(o.seed),
        options.pressure_mpa, options.frequency_hz, options.health.baseline_s,
        options.healthy_s / 60.0, options.blockage * 100.0);
    std::printf("%8s %8s %8s %10s %12s %16s %17s\n", "machine", "blocked", "named", "after_s",
                "false_alarm", "healthy_scatter", "healthy_evidence");
    for (std::size_t i = 0; i < r.machines.size(); ++i) {
      const auto& m = r.machines[i];
      std::printf("%8zu %8d %8d %10.2f %12s %16.3f %17.2f\n", i + 1, m.blocked_nozzle + 1,
                  m.named_nozzle + 1, m.detect_s, m.false_alarm ? "YES" : "no",
                  m.healthy_worst_deviation, m.healthy_max_evidence);
    }
    std::printf(
        "named within %.0f s: %d of %d; false alarms: %d in %.0f healthy machine-minutes; "
        "time to name: mean %.2f s, sd %.2f, worst %.2f; healthy scatter (largest |ratio - 1|): "
        "mean %.3f, worst %.3f",
        options.detect_limit_s, r.named_within_limit, fleet.plants, r.false_alarms,
        r.healthy_minutes, r.detect_s.mean, r.detect_s.sd, r.detect_s.worst,
        r.healthy_worst_deviation.mean, r.healthy_worst_deviation.worst);
    if (options.health.judge == control::NozzleJudge::kCusum)
      std::printf("; healthy evidence (largest, alarm above %.0f): mean %.2f, sd %.2f, worst %.2f",
                  options.health.alarm_threshold, r.healthy_max_evidence.mean,
                  r.healthy_max_evidence.sd, r.healthy_max_evidence.worst);
    std::printf("\n");
  }
  return 0;
}

int run_linearity_fleet_command(const ExperimentOptions& o) {
  const ex::LinearityFleetResult r = ex::run_linearity_fleet({o.seed, o.plants, true});
  if (o.json) {
    std::printf("{\"plants\": %d, \"seed\": %llu, \"changed_after_calibration\": true, ", o.plants,
                static_cast<unsigned long long>(o.seed));
    print_spread_json("r2", r.r2);
    print_spread_json("mean_error_pct", r.mean_error_pct);
    print_spread_json("max_error_pct", r.max_error_pct, false);
    std::printf("}\n");
  } else {
    std::printf(
        "nozzle 1 swept 10-100 %%, 0.2 MPa, 3 Hz, %d drawn machines (seed %llu), "
        "calibrated as made, then changed; trim on\n",
        o.plants, static_cast<unsigned long long>(o.seed));
    std::printf("%-34s%12s%12s%12s\n", "over the machines", "mean", "sd", "worst");
    print_spread_row("R2 (worst = lowest)", r.r2, "%12.5f");
    print_spread_row("mean error [%]", r.mean_error_pct, "%12.3f");
    print_spread_row("max error [%]", r.max_error_pct, "%12.3f");
  }
  return 0;
}

int run_calibrate_fleet_command(const ExperimentOptions& o) {
  const ex::CalibrationFleetResult r = ex::run_calibration_fleet({o.seed, o.plants, false});
  if (o.json) {
    std::printf("{\"plants\": %d, \"seed\": %llu, ", o.plants,
                static_cast<unsigned long long>(o.seed));
    print_spread_json("meter_error_pct", r.meter_error_pct);
    print_spread_json("full_open_error_pct", r.full_open_error_pct);
    print_spread_json("line_error_pct", r.line_error_pct);
    print_spread_json("r2", r.r2, false);
    std::printf("}\n");
  } else {
    std::printf(
        "catch test + per-nozzle lines (each nozzle alone, one line meter), 0.2 MPa, 3 Hz, "
        "%d drawn machines as made (seed %llu)\n",
        o.plants, static_cast<unsigned long long>(o.seed));
    std::printf("%-34s%12s%12s%12s\n", "over the machines", "mean", "sd", "worst");
    print_spread_row("meter K error after catch [%]", r.meter_error_pct, "%12.4f");
    print_spread_row("worst nozzle full-open error [%]", r.full_open_error_pct, "%12.3f");
    print_spread_row("worst nozzle line error 20-80 [%]", r.line_error_pct, "%12.3f");
    print_spread_row("lowest nozzle R2", r.r2, "%12.5f");
  }
  return 0;
}

int run_ripple_command(const ExperimentOptions& o) {
  if (o.plants > 0) return run_ripple_fleet_command(o);
  ex::RippleOptions options;
  options.seed = o.seed;
  const ex::RippleResult r = ex::run_ripple(options);
  const double ratio = r.staggered.pp_mpa > 0 ? r.synchronous.pp_mpa / r.staggered.pp_mpa : 0.0;
  if (o.json) {
    std::printf(
        "{\"synchronous_pp_mpa\": %.5f, \"staggered_pp_mpa\": %.5f, \"ratio\": %.2f, "
        "\"duty_pct\": %.0f, \"frequency_hz\": %.1f}\n",
        r.synchronous.pp_mpa, r.staggered.pp_mpa, ratio, options.duty_pct, options.frequency_hz);
  } else {
    std::printf("4 nozzles at %.0f %% duty, %.0f Hz, fuzzy PID at 0.2 MPa (UGV Fig. 8)\n",
                options.duty_pct, options.frequency_hz);
    std::printf("%-12s %18s\n", "PWM", "pressure p-p [MPa]");
    std::printf("%-12s %18.5f\n%-12s %18.5f\nsynchronous / staggered = %.1f x\n", "synchronous",
                r.synchronous.pp_mpa, "staggered", r.staggered.pp_mpa, ratio);
  }
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

int run_calibrate_command(const ExperimentOptions& o) {
  if (o.plants > 0) return run_calibrate_fleet_command(o);
  ex::CalibrationOptions options;
  options.seed = o.seed;
  const ex::CalibrationResult r = ex::run_calibration(options);
  if (o.json) {
    std::printf(
        "{\"meter_k_error_pct\": %.4f, \"meter_pulses_per_litre\": %.2f, "
        "\"true_pulses_per_litre\": %.2f, \"meter_calibration_error_pct\": %.4f, \"nozzles\": [",
        r.meter_k_error_pct, r.meter.pulses_per_litre, r.true_pulses_per_litre,
        r.meter_calibration_error_pct);
    for (std::size_t i = 0; i < r.nozzles.size(); ++i) {
      const auto& n = r.nozzles[i];
      std::printf(
          "%s{\"a\": %.6f, \"b\": %.5f, \"true_a\": %.6f, \"true_b\": %.5f, \"r2\": %.6f, "
          "\"full_open_l_per_min\": %.5f, \"true_full_open_l_per_min\": %.5f}",
          i ? ", " : "", n.fitted.slope_l_per_min_per_pct, n.fitted.intercept_l_per_min,
          n.truth.slope_l_per_min_per_pct, n.truth.intercept_l_per_min, n.r_squared,
          n.full_open_l_per_min, n.true_full_open_l_per_min);
    }
    std::printf("]}\n");
  } else {
    std::printf(
        "catch test: label 8500 pulses/L, measured %.1f, true %.1f (label error %.2f %%, "
        "calibration error %.3f %%)\n",
        r.meter.pulses_per_litre, r.true_pulses_per_litre, r.meter_k_error_pct,
        r.meter_calibration_error_pct);
    std::printf("nozzle lines q = A s + b at %.2f MPa, %.0f Hz (each nozzle alone, one meter)\n",
                options.pressure_mpa, options.frequency_hz);
    std::printf("%6s %10s %8s %10s %8s %9s %10s %10s\n", "nozzle", "A", "b", "true A", "true b",
                "R2", "full-open", "true full");
    for (std::size_t i = 0; i < r.nozzles.size(); ++i) {
      const auto& n = r.nozzles[i];
      std::printf("%6zu %10.6f %8.5f %10.6f %8.5f %9.6f %10.5f %10.5f\n", i + 1,
                  n.fitted.slope_l_per_min_per_pct, n.fitted.intercept_l_per_min,
                  n.truth.slope_l_per_min_per_pct, n.truth.intercept_l_per_min, n.r_squared,
                  n.full_open_l_per_min, n.true_full_open_l_per_min);
    }
  }
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

void print_duty_point_json(const ex::DutyPoint& p) {
  std::printf(
      "{\"duty_pct\": %.1f, \"commanded_duty_pct\": %.3f, \"requested_l\": %.6f, \"delivered_l\": "
      "%.6f, \"error_pct\": %.4f}",
      p.duty_pct, p.commanded_duty_pct, p.requested_l, p.delivered_l, p.error_pct);
}

int run_linearity_command(const ExperimentOptions& o) {
  if (o.plants > 0) return run_linearity_fleet_command(o);
  ex::SprayRunOptions options;
  options.seed = o.seed;
  options.raw = o.raw;
  const ex::LinearityResult r = ex::run_linearity(options);
  if (o.json) {
    std::printf(
        "{\"raw\": %s, \"r2\": %.6f, \"mean_error_pct\": %.4f, \"max_error_pct\": %.4f, "
        "\"points\": [",
        r.raw ? "true" : "false", r.r2, r.mean_error_pct, r.max_error_pct);
    for (std::size_t i = 0; i < r.points.size(); ++i) {
      if (i) std::printf(", ");
      print_duty_point_json(r.points[i]);
    }
    std::printf("]}\n");
  } else {
    std::printf("nozzle 1 swept, nozzles 2-4 at 100 %%, 0.2 MPa, 3 Hz, 30 s per point (%s)\n",
                r.raw ? "RAW: no calibration/compensation/feedback, synchronous"
                      : "calibrated, compensated, flow feedback, staggered");
    std::printf("%6s %10s %12s %12s %8s\n", "duty%", "commanded%", "requested_L", "delivered_L",
                "error%");
    for (const auto& p : r.points)
      std::printf("%6.0f %10.2f %12.5f %12.5f %8.2f\n", p.duty_pct, p.commanded_duty_pct,
                  p.requested_l, p.delivered_l, p.error_pct);
    std::printf("R2 %.5f  mean error %.2f %%  max error %.2f %%\n", r.r2, r.mean_error_pct,
                r.max_error_pct);
  }
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

int run_orthogonal_command(const ExperimentOptions& o) {
  if (o.plants > 0) return run_orthogonal_fleet_command(o);
  ex::SprayRunOptions options;
  options.seed = o.seed;
  options.raw = o.raw;
  const ex::OrthogonalResult r = ex::run_orthogonal(options);
  if (o.json) {
    std::printf(
        "{\"raw\": %s, \"mean_error_pct\": %.4f, \"max_error_pct\": %.4f, "
        "\"pressure_band_mpa\": %.5f, \"runs\": [",
        r.raw ? "true" : "false", r.mean_error_pct, r.max_error_pct, r.pressure_band_mpa);
    for (std::size_t i = 0; i < r.runs.size(); ++i) {
      std::printf("%s{\"run\": %zu, \"pressure_band_mpa\": %.5f, \"nozzles\": [", i ? ", " : "",
                  i + 1, r.runs[i].pressure_band_mpa);
      for (std::size_t k = 0; k < 4; ++k) {
        if (k) std::printf(", ");
        print_duty_point_json(r.runs[i].nozzles[k]);
      }
      std::printf("]}");
    }
    std::printf("]}\n");
  } else {
    std::printf("L16 orthogonal test, 0.2 MPa, 3 Hz, 30 s per run (%s)\n",
                r.raw ? "RAW: no calibration/compensation/feedback, synchronous"
                      : "calibrated, compensated, flow feedback, staggered");
    std::printf("%4s %23s   %31s %10s\n", "run", "duty A B C D [%]", "error A B C D [%]",
                "band MPa");
    for (std::size_t i = 0; i < r.runs.size(); ++i) {
      const auto& n = r.runs[i].nozzles;
      std::printf("%4zu %5.0f %5.0f %5.0f %5.0f   %7.2f %7.2f %7.2f %7.2f %10.4f\n", i + 1,
                  n[0].duty_pct, n[1].duty_pct, n[2].duty_pct, n[3].duty_pct, n[0].error_pct,
                  n[1].error_pct, n[2].error_pct, n[3].error_pct, r.runs[i].pressure_band_mpa);
    }
    std::printf("mean error %.2f %%  max error %.2f %%  pressure band %.4f MPa\n", r.mean_error_pct,
                r.max_error_pct, r.pressure_band_mpa);
  }
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

int run_dose_fleet_command(const ExperimentOptions& o) {
  const ex::DoseFleetResult r = ex::run_dose_fleet({o.seed, o.plants, true});
  if (o.json) {
    std::printf("{\"plants\": %d, \"seed\": %llu, \"changed_after_calibration\": true, ", o.plants,
                static_cast<unsigned long long>(o.seed));
    for (const auto* row : {&r.trim_on, &r.trim_off})
      print_spreads_json(row == &r.trim_on ? "trim_on" : "trim_off",
                         {{"r2", &row->r2},
                          {"mean_error_pct", &row->mean_error_pct},
                          {"max_error_pct", &row->max_error_pct}},
                         row == &r.trim_on);
    std::printf("}\n");
  } else {
    std::printf(
        "wheat paper dose check (densities 0.40-0.75, 1 m/s, 0.4 MPa, 5 Hz, nozzle 1), %d drawn "
        "machines (seed %llu), each calibrated as made, then changed\n",
        o.plants, static_cast<unsigned long long>(o.seed));
    std::printf("%-34s%12s%12s%12s\n", "over the machines", "mean", "sd", "worst");
    for (const auto* row : {&r.trim_on, &r.trim_off}) {
      std::printf("-- online flow trim %s\n", row == &r.trim_on ? "ON" : "OFF");
      print_spread_row("R2 (worst = lowest)", row->r2, "%12.5f");
      print_spread_row("mean error [%]", row->mean_error_pct, "%12.3f");
      print_spread_row("max error [%]", row->max_error_pct, "%12.3f");
    }
  }
  return 0;
}

int run_dose_command(const ExperimentOptions& o) {
  if (o.plants > 0) return run_dose_fleet_command(o);
  ex::DoseOptions options;
  options.seed = o.seed;
  const ex::DoseResult r = ex::run_dose(options);
  if (o.json) {
    std::printf("{\"r2\": %.6f, \"mean_error_pct\": %.4f, \"points\": [", r.r2, r.mean_error_pct);
    for (std::size_t i = 0; i < r.points.size(); ++i)
      std::printf(
          "%s{\"density\": %.3f, \"theoretical_l_per_min\": %.5f, "
          "\"delivered_l_per_min\": %.5f, \"duty_pct\": %.3f}",
          i ? ", " : "", r.points[i].density, r.points[i].theoretical_l_per_min,
          r.points[i].delivered_l_per_min, r.points[i].duty_pct);
    std::printf("]}\n");
  } else {
    std::printf("wheat paper dose check: 1 m/s, 0.4 MPa, 5 Hz, k = %.2f, 60 s per density\n",
                options.max_density);
    std::printf("%8s %16s %16s %8s\n", "density", "theory L/min", "delivered L/min", "duty%");
    for (const auto& p : r.points)
      std::printf("%8.2f %16.4f %16.4f %8.2f\n", p.density, p.theoretical_l_per_min,
                  p.delivered_l_per_min, p.duty_pct);
    std::printf("R2 %.5f (paper: 0.968)  mean error %.2f %%\n", r.r2, r.mean_error_pct);
  }
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
    const ex::SavingsFleetResult f =
        ex::run_savings_fleet(field.weed_density, {o.seed, o.plants, false}, options);
    if (o.json) {
      std::printf(
          "{\"plants\": %d, \"seed\": %llu, \"changed_after_calibration\": false, "
          "\"images\": %zu, \"weed_source\": \"%s\", \"decision_threshold\": %.4f, ",
          o.plants, static_cast<unsigned long long>(o.seed), photos.size(), o.weed_source.c_str(),
          options.decision_threshold);
      print_spread_json("savings_pct", f.savings_pct);
      print_spread_json("under_dosed_pct", f.under_dosed_pct);
      print_spread_json("uniform_l", f.uniform_l);
      print_spread_json("variable_l", f.variable_l, false);
      std::printf("}\n");
    } else {
      std::printf(
          "savings at equal coverage, %zu photos, weed density: %s, %d drawn machines (seed "
          "%llu) as made\n",
          photos.size(), o.weed_source.c_str(), o.plants, static_cast<unsigned long long>(o.seed));
      std::printf("%-34s%12s%12s%12s\n", "over the machines", "mean", "sd", "worst");
      print_spread_row("savings [%] (worst = lowest)", f.savings_pct, "%12.2f");
      print_spread_row("under-dosed nozzle-zones [%]", f.under_dosed_pct, "%12.2f");
      print_spread_row("uniform [L]", f.uniform_l, "%12.3f");
      print_spread_row("variable [L]", f.variable_l, "%12.3f");
    }
    return 0;
  }
  const ex::SavingsResult r = ex::run_savings(field.weed_density, options);
  const ex::SavingsRun& clamp = r.spec_clamp;
  const ex::TruthTally equal_truth = ex::tally_against_truth(r.equal_coverage, field.truth);
  const ex::TruthTally clamp_truth = ex::tally_against_truth(clamp, field.truth);
  if (o.json) {
    // Headline = equal coverage (every zone above the decision threshold sprayed at least at
    // the minimum duty); spec_clamp_* = the SPEC clamp (< 20 % duty -> closed).
    std::printf(
        "{\"images\": %zu, \"weed_source\": \"%s\", \"decision_threshold\": %.4f, "
        "\"savings_pct\": %.3f, "
        "\"weedy_zones\": %d, \"weedy_left_dry\": %d, \"crop_only_zones\": %d, "
        "\"crop_only_sprayed\": %d, \"under_dosed_zones\": %d, \"zones\": %d, "
        "\"variable_l\": %.4f, \"uniform_l\": %.4f, "
        "\"nozzle_savings_pct\": [%.2f, %.2f, %.2f, %.2f], \"policy\": \"equal_coverage\", "
        "\"spec_clamp_savings_pct\": %.3f, \"spec_clamp_weedy_left_dry\": %d, "
        "\"spec_clamp_crop_only_sprayed\": %d, \"spec_clamp_under_dosed_zones\": %d, "
        "\"spec_clamp_variable_l\": %.4f, \"scheduler\": \"NozzleScheduler\"}\n",
        photos.size(), o.weed_source.c_str(), options.decision_threshold, r.savings_pct,
        equal_truth.weedy_zones, equal_truth.weedy_left_dry, equal_truth.crop_only_zones,
        equal_truth.crop_only_sprayed, r.under_dosed_zones, r.zones, r.variable_l, r.uniform_l,
        r.nozzle_savings_pct[0], r.nozzle_savings_pct[1], r.nozzle_savings_pct[2],
        r.nozzle_savings_pct[3], clamp.savings_pct, clamp_truth.weedy_left_dry,
        clamp_truth.crop_only_sprayed, clamp.under_dosed_zones, clamp.variable_l);
  } else {
    std::printf(
        "field: %zu zones of %.1f m x 4 nozzles from %zu photos in %s%s%s (2x4 grid per "
        "photo), weed density: %s, decision threshold %.3f\n",
        field.weed_density.size(), options.zone_length_m, photos.size(), images.c_str(),
        o.stems_file.empty() ? "" : " listed in ", o.stems_file.c_str(), o.weed_source.c_str(),
        options.decision_threshold);
    std::printf(
        "truth (%s): %d weedy nozzle-zones (true weed >= 0.5 %%), %d crop-only nozzle-zones\n",
        masks.c_str(), equal_truth.weedy_zones, equal_truth.crop_only_zones);
    std::printf("decisions pinned to ground intervals by the NozzleScheduler (1.2 m boom)\n");
    std::printf("uniform %.3f L\n", r.uniform_l);
    std::printf(
        "equal coverage (weedy zones >= min duty): variable %.3f L  savings %.1f %%  weedy left "
        "dry %d  crop-only sprayed %d  under-dosed %d of %d\n",
        r.variable_l, r.savings_pct, equal_truth.weedy_left_dry, equal_truth.crop_only_sprayed,
        r.under_dosed_zones, r.zones);
    std::printf(
        "SPEC clamp (< 20 %% duty closed):         variable %.3f L  savings %.1f %%  weedy left "
        "dry %d  crop-only sprayed %d  under-dosed %d of %d\n",
        clamp.variable_l, clamp.savings_pct, clamp_truth.weedy_left_dry,
        clamp_truth.crop_only_sprayed, clamp.under_dosed_zones, r.zones);
    std::printf("per nozzle savings (equal coverage) %.1f %.1f %.1f %.1f %% (paper: 46.3 %%)\n",
                r.nozzle_savings_pct[0], r.nozzle_savings_pct[1], r.nozzle_savings_pct[2],
                r.nozzle_savings_pct[3]);
  }
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

int run_experiment(const ExperimentOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  int rc = 0;
  if (o.name == "step")
    rc = run_step_command(o);
  else if (o.name == "ripple")
    rc = run_ripple_command(o);
  else if (o.name == "calibrate")
    rc = run_calibrate_command(o);
  else if (o.name == "linearity")
    rc = run_linearity_command(o);
  else if (o.name == "orthogonal")
    rc = run_orthogonal_command(o);
  else if (o.name == "dose")
    rc = run_dose_command(o);
  else if (o.name == "blockage")
    rc = run_blockage_command(o);
  else if (o.name == "savings")
    rc = run_savings_command(o);
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
  cmd->add_option("name", options->name,
                  "step | ripple | linearity | orthogonal | dose | calibrate | savings | blockage")
      ->required()
      ->check(CLI::IsMember({"step", "ripple", "linearity", "orthogonal", "dose", "calibrate",
                             "savings", "blockage"}));
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
                  "blockage: the nozzle health detector's judge (control/nozzle_health.hpp)")
      ->check(CLI::IsMember({"band", "cusum"}));
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
