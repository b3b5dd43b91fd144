// SPDX-License-Identifier: Apache-2.0
// Start-up step 0 -> set-point with the conventional PID and the fuzzy PID (UGV Fig. 7), and
// the documented tuning search behind the default gains.
#include <algorithm>
#include <cmath>
#include <vector>

#include "lab/experiments/experiments.hpp"
#include "lab/experiments/vocabulary.hpp"

namespace weedspray::lab::experiments {
namespace {

StepMetrics metrics_of(const std::vector<TraceSample>& trace, double setpoint) {
  std::vector<double> t(trace.size()), p(trace.size());
  for (std::size_t i = 0; i < trace.size(); ++i) {
    t[i] = trace[i].time_s;
    p[i] = trace[i].pressure_mpa;
  }
  return step_metrics(t, p, setpoint);
}

// Grid search around `centre`, each gain multiplied by the factors; returns the best by ITAE.
template <typename Evaluate>
PidGains search_gains(PidGains centre, const std::vector<double>& factors, bool with_kd,
                      Evaluate&& evaluate, double& best_itae, int& count) {
  PidGains best = centre;
  for (double fp : factors)
    for (double fi : factors)
      for (double fd : with_kd ? factors : std::vector<double>{1.0}) {
        const PidGains g{centre.kp * fp, centre.ki * fi, centre.kd * fd};
        const double itae = evaluate(g);
        ++count;
        if (itae < best_itae) {
          best_itae = itae;
          best = g;
        }
      }
  return best;
}

}  // namespace

StepRun run_step_once(PressureControlMode mode, const FuzzyPidConfig& config,
                      const StepOptions& options) {
  RigConfig rig_config;
  rig_config.seed = options.seed;
  rig_config.controller_mode = mode;
  rig_config.controller = config;
  rig_config.setpoint_mpa = options.setpoint_mpa;
  rig_config.fixes = {true, false, false};
  rig_config.record_period_s = 0.002;
  rig_config.control_period_s = options.control_period_s;
  rig_config.converter_lead_s = options.converter_lead_s;
  rig_config.converter_lag_s = options.converter_lag_s;
  rig_config.plant = options.plant;
  ClosedLoopRig rig(rig_config);
  // Start-up with the boom spraying: every nozzle open (100 % duty) as in the paper's bench,
  // or the first nozzles_open of them.
  const int n = rig.plant().nozzle_count();
  const int open = options.nozzles_open < 0 ? n : std::min(options.nozzles_open, n);
  std::vector<double> full(static_cast<std::size_t>(n), 0.0);
  std::fill_n(full.begin(), open, 100.0);
  rig.command_duties(full);
  rig.start();
  rig.run_for(options.duration_s);
  StepRun run;
  run.trace = rig.trace();
  run.metrics = metrics_of(run.trace, options.setpoint_mpa);
  run.gains = config.base.gains;
  return run;
}

StepResult run_step(const StepOptions& options) {
  StepResult result;
  result.setpoint_mpa = options.setpoint_mpa;
  FuzzyPidConfig pid_config = options.fuzzy;
  pid_config.base.gains = options.pid_gains;
  result.pid = run_step_once(PressureControlMode::kPid, pid_config, options);
  result.fuzzy_pid = run_step_once(PressureControlMode::kFuzzyPid, options.fuzzy, options);
  result.fuzzy_correction_weights = options.fuzzy.correction_weights;
  return result;
}

TuningResult tune_step_controllers(const StepOptions& options) {
  TuningResult result;
  StepOptions quick = options;
  // Conventional PID: coarse log grid over three decades, then two finer passes.
  auto eval_pid = [&](const PidGains& g) {
    FuzzyPidConfig c = options.fuzzy;
    c.base.gains = g;
    return run_step_once(PressureControlMode::kPid, c, quick).metrics.itae;
  };
  double best = 1e30;
  PidGains pid = search_gains({4.0, 16.0, 0.01}, {0.125, 0.25, 0.5, 1, 2, 4, 8}, true, eval_pid,
                              best, result.candidates_evaluated);
  pid = search_gains(pid, {0.6, 0.8, 1.0, 1.25, 1.6}, true, eval_pid, best,
                     result.candidates_evaluated);
  pid = search_gains(pid, {0.9, 1.0, 1.1}, true, eval_pid, best, result.candidates_evaluated);
  result.pid = pid;
  FuzzyPidConfig pid_config = options.fuzzy;
  pid_config.base.gains = pid;
  result.pid_metrics = run_step_once(PressureControlMode::kPid, pid_config, quick).metrics;

  // Fuzzy PID: correction weights on a grid (in units of the base gain per quantised unit),
  // then the base gains re-searched with the best weights, then the weights once more.
  FuzzyPidConfig fuzzy = options.fuzzy;
  fuzzy.base.gains = pid;
  // Every candidate shares the one process-wide query table (it does not depend on gains or
  // weights), so the search runs at the configured resolution.
  auto eval_fuzzy = [&](const FuzzyPidConfig& c) {
    return run_step_once(PressureControlMode::kFuzzyPid, c, quick).metrics.itae;
  };
  auto search_weights = [&](FuzzyPidConfig c, double& best_itae) {
    const PidGains b = c.base.gains;
    FuzzyPidConfig best_config = c;
    for (double wp : {0.0, 0.02, 0.05, 0.1, 0.2})
      for (double wi : {0.0, 0.02, 0.05, 0.1, 0.2})
        for (double wd : {0.0, 0.05, 0.1, 0.2}) {
          c.correction_weights = {b.kp * wp, b.ki * wi, b.kd * wd};
          const double itae = eval_fuzzy(c);
          ++result.candidates_evaluated;
          if (itae < best_itae) {
            best_itae = itae;
            best_config = c;
          }
        }
    return best_config;
  };
  double best_fuzzy = 1e30;
  fuzzy = search_weights(fuzzy, best_fuzzy);
  const PidGains ratio_base = fuzzy.base.gains;
  const PidGains weights = fuzzy.correction_weights;
  auto eval_base = [&](const PidGains& g) {
    FuzzyPidConfig c = fuzzy;
    c.base.gains = g;
    // Keep the weights proportional to the base gains.
    c.correction_weights = {weights.kp * g.kp / ratio_base.kp, weights.ki * g.ki / ratio_base.ki,
                            ratio_base.kd > 0 ? weights.kd * g.kd / ratio_base.kd : weights.kd};
    return eval_fuzzy(c);
  };
  const PidGains base = search_gains(fuzzy.base.gains, {0.6, 0.8, 1.0, 1.25, 1.6}, true, eval_base,
                                     best_fuzzy, result.candidates_evaluated);
  fuzzy.correction_weights = {
      weights.kp * base.kp / ratio_base.kp, weights.ki * base.ki / ratio_base.ki,
      ratio_base.kd > 0 ? weights.kd * base.kd / ratio_base.kd : weights.kd};
  fuzzy.base.gains = base;
  fuzzy = search_weights(fuzzy, best_fuzzy);
  result.fuzzy = fuzzy;
  result.fuzzy_metrics = run_step_once(PressureControlMode::kFuzzyPid, fuzzy, quick).metrics;
  return result;
}

}  // namespace weedspray::lab::experiments
