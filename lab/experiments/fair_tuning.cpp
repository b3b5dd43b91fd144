// SPDX-License-Identifier: Apache-2.0
#include "lab/experiments/fair_tuning.hpp"
#include "lab/experiments/vocabulary.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace weedspray::lab::experiments {
namespace {

struct Bound {
  double lo;
  double hi;
  bool log;
};
constexpr std::array<Bound, 6> kBounds = {{
    {1.0, 1000.0, true},   // Kp [1/MPa]
    {1.0, 10000.0, true},  // Ki [1/(MPa s)]
    {1e-4, 10.0, true},    // Kd [s/MPa]
    {0.0, 0.3, false},     // Cp / Kp'
    {0.0, 0.3, false},     // Ci / Ki'
    {0.0, 0.3, false},     // Cd / Kd'
}};

double map(const Bound& b, double x) {
  return b.log ? b.lo * std::pow(b.hi / b.lo, x) : b.lo + (b.hi - b.lo) * x;
}

FuzzyPidConfig config_of(const std::vector<double>& x) {
  FuzzyPidConfig c = default_fuzzy_pid_config();
  c.base.gains = {map(kBounds[0], x[0]), map(kBounds[1], x[1]), map(kBounds[2], x[2])};
  c.correction_weights = {};
  if (x.size() == 6)
    c.correction_weights = {c.base.gains.kp * map(kBounds[3], x[3]),
                            c.base.gains.ki * map(kBounds[4], x[4]),
                            c.base.gains.kd * map(kBounds[5], x[5])};
  return c;
}

TunedController compass_search(PressureControlMode mode, std::vector<double> x,
                               const TuningSet& set, int budget) {
  TunedController out;
  auto evaluate = [&](const std::vector<double>& at) {
    ++out.evaluations;
    return mean_itae(mode, config_of(at), set);
  };
  double best = evaluate(x);
  double step = 0.25;
  while (out.evaluations < budget) {
    std::vector<double> best_x = x;
    double best_here = best;
    for (std::size_t d = 0; d < x.size() && out.evaluations < budget; ++d)
      for (double sign : {-1.0, 1.0}) {
        if (out.evaluations >= budget) break;
        std::vector<double> y = x;
        y[d] = std::clamp(y[d] + sign * step, 0.0, 1.0);
        if (y[d] == x[d]) continue;
        const double v = evaluate(y);
        if (v < best_here) {
          best_here = v;
          best_x = y;
        }
      }
    if (best_here < best) {
      best = best_here;
      x = best_x;
    } else {
      step *= 0.5;
    }
  }
  out.config = config_of(x);
  out.training_itae = best;
  for (std::size_t d = 0; d < 3; ++d) out.on_bound |= x[d] <= 0.0 || x[d] >= 1.0;
  for (std::size_t d = 3; d < x.size(); ++d) out.on_bound |= x[d] >= 1.0;  // 0 = no correction
  return out;
}

}  // namespace

StepOptions daemon_step_timing() {
  StepOptions o;
  o.control_period_s = 0.010;
  o.converter_lead_s = 0.0025;
  o.converter_lag_s = 0.001;
  o.duration_s = 3.0;
  return o;
}

TuningSet training_set(std::uint64_t seed, int machines, const StepOptions& timing) {
  TuningSet set;
  set.machines = draw_machines(seed, machines, 1000);
  set.points = {{0.2, 4}, {0.3, 1}, {0.4, 2}, {0.5, 3}};
  set.timing = timing;
  return set;
}

StepScore score_step(PressureControlMode mode, const FuzzyPidConfig& config, const Machine& machine,
                     const OperatingPoint& point, const StepOptions& timing) {
  StepOptions o = timing;
  o.seed = machine.seed;
  o.plant = machine.params;
  o.setpoint_mpa = point.setpoint_mpa;
  o.nozzles_open = point.nozzles_open;
  const StepRun run = run_step_once(mode, config, o);
  return {run.metrics.itae, run.metrics.overshoot_pct, run.metrics.settle_s, run.metrics.settled};
}

double mean_itae(PressureControlMode mode, const FuzzyPidConfig& config, const TuningSet& set) {
  double sum = 0.0;
  int n = 0;
  for (const Machine& m : set.machines)
    for (const OperatingPoint& p : set.points) {
      sum += score_step(mode, config, m, p, set.timing).itae;
      ++n;
    }
  return n > 0 ? sum / n : 0.0;
}

FairTuningResult tune_fair(const TuningSet& set, int budget) {
  FairTuningResult r;
  r.pid = compass_search(PressureControlMode::kPid, {0.5, 0.5, 0.5}, set, budget);
  r.fuzzy_pid = compass_search(PressureControlMode::kFuzzyPid,
                               {0.5, 0.5, 0.5, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0}, set, budget);
  return r;
}

StepFleetResult run_step_fleet(const FleetOptions& fleet, const FuzzyPidConfig& pid,
                               const FuzzyPidConfig& fuzzy_pid,
                               const std::vector<double>& setpoints_mpa,
                               const StepOptions& timing) {
  const std::vector<Machine> machines = draw_machines(fleet.seed, fleet.plants);
  const TuningSet points = training_set(fleet.seed, 0, timing);
  auto judge = [&](PressureControlMode mode, const FuzzyPidConfig& config) {
    StepFleetController out;
    for (double sp : setpoints_mpa) {
      StepFleetRow row;
      row.setpoint_mpa = sp;
      std::vector<double> overshoot, settle, itae;
      for (const Machine& m : machines) {
        const StepScore s = score_step(mode, config, m, {sp, 4}, points.timing);
        overshoot.push_back(s.overshoot_pct);
        settle.push_back(s.settle_s);
        itae.push_back(s.itae);
        row.unsettled += s.settled ? 0 : 1;
      }
      row.overshoot_pct = spread_of(overshoot);
      row.settle_s = spread_of(settle);
      row.itae = spread_of(itae);
      out.rows.push_back(row);
    }
    std::vector<double> per_machine;
    for (const Machine& m : machines) {
      TuningSet one = points;
      one.machines = {m};
      per_machine.push_back(mean_itae(mode, config, one));
    }
    out.operating_points_itae = spread_of(per_machine);
    return out;
  };
  return {judge(PressureControlMode::kPid, pid), judge(PressureControlMode::kFuzzyPid, fuzzy_pid)};
}

// Recorded from `weedspray-lab experiment step --plants 20 --tune --tune-budget 300` (seed 1:
// training machines 1000-1004 at 0.2/4, 0.3/1, 0.4/2, 0.5/3 MPa/nozzles, 100 Hz, ADC lead
// 2.5 ms, DAC lag 1 ms; 211 s). Training ITAE: PID 0.043883, fuzzy PID 0.042957. The PID
// result was the same with budget 150 (converged); the fuzzy PID's improved 0.7 % from 150 to
// 300 (six coordinates). Neither ended on a bound (Cd = 0: the D correction did not help).
FuzzyPidConfig fair_tuned_pid_config() {
  FuzzyPidConfig c = default_fuzzy_pid_config();
  c.base.gains = {39.31, 392.4, 0.9222};
  c.correction_weights = {};
  return c;
}

FuzzyPidConfig fair_tuned_fuzzy_pid_config() {
  FuzzyPidConfig c = default_fuzzy_pid_config();
  c.base.gains = {33.38, 352.3, 1.009};
  c.correction_weights = {0.7823, 45.96, 0.0};
  return c;
}

}  // namespace weedspray::lab::experiments
