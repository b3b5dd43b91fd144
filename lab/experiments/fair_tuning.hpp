// SPDX-License-Identifier: Apache-2.0
// Fair tuning of the pressure controllers: ONE search, the same budget and the same
// bounds for the conventional PID and the fuzzy PID, on a training set of machines and
// operating points, judged on other machines.
//
// The search: a compass (pattern) search in normalised coordinates x in [0, 1]^d. Gains map
// log-uniformly onto their bounds (Kp 1-1000, Ki 1-10000, Kd 1e-4-10: three to four decades,
// so neither controller's optimum sits on a bound; tune_fair() reports if one does); the fuzzy
// PID's three correction weights map linearly onto [0, 0.3] x its base gain (at 0.3 the
// corrections swing a gain by up to +-160 %). Both start from the same base gains (the centre
// of the box), the fuzzy weights from 0.1. Each iteration polls x +- step on every coordinate,
// moves to the best improvement, halves the step when none improves; it stops only when the
// evaluation budget is spent (never on a boundary or a small step). The objective is the mean
// ITAE over every (machine, operating point) of the training set, each a 3 s start-up from a
// fully open return valve with the daemon's loop timing.
#pragma once

#include <cstdint>
#include <vector>

#include "lab/experiments/experiments.hpp"
#include "lab/experiments/vocabulary.hpp"

namespace weedspray::lab::experiments {

struct OperatingPoint {
  double setpoint_mpa = 0.2;
  int nozzles_open = 4;
};

struct TuningSet {
  std::vector<Machine> machines;
  std::vector<OperatingPoint> points;
  StepOptions timing;  // control period, converter lead/lag, duration
};

// The daemon's loop (pressure.loop_hz = 100; io::AnalogIoWorker: ADC 2.5 ms before each tick,
// DAC 1 ms after it).
StepOptions daemon_step_timing();
// Training set: machines 1000.. of fleet `seed` (never the held-out 0..N-1) at 0.2-0.5 MPa with
// 1-4 nozzles open.
TuningSet training_set(std::uint64_t seed, int machines = 5,
                       const StepOptions& timing = daemon_step_timing());

struct StepScore {
  double itae = 0.0;
  double overshoot_pct = 0.0;
  double settle_s = 0.0;
  bool settled = false;
};
StepScore score_step(PressureControlMode mode, const FuzzyPidConfig& config, const Machine& machine,
                     const OperatingPoint& point, const StepOptions& timing);
double mean_itae(PressureControlMode mode, const FuzzyPidConfig& config, const TuningSet& set);

struct TunedController {
  FuzzyPidConfig config{};
  double training_itae = 0.0;
  int evaluations = 0;
  bool on_bound = false;  // a gain or weight ended on its bound (widen the bounds)
};
struct FairTuningResult {
  TunedController pid;
  TunedController fuzzy_pid;
};
FairTuningResult tune_fair(const TuningSet& set, int budget = 300);

// Both controllers judged on held-out machines (draw_machines(seed, plants): indices 0..N-1)
// with the daemon's timing: a start-up with 4 nozzles open at each set-point, and the mean ITAE
// over the training set's operating points (0.2-0.5 MPa, 1-4 nozzles) on the same machines.
struct StepFleetRow {
  double setpoint_mpa = 0.0;
  Spread overshoot_pct, settle_s, itae;
  int unsettled = 0;  // machines still outside the +-2 % band at the end of the 3 s record
};
struct StepFleetController {
  std::vector<StepFleetRow> rows;  // one per set-point
  Spread operating_points_itae;    // per machine: mean ITAE over the operating points
};
struct StepFleetResult {
  StepFleetController pid;
  StepFleetController fuzzy_pid;
};
StepFleetResult run_step_fleet(const FleetOptions& fleet, const FuzzyPidConfig& pid,
                               const FuzzyPidConfig& fuzzy_pid,
                               const std::vector<double>& setpoints_mpa = {0.2, 0.4},
                               const StepOptions& timing = daemon_step_timing());

// The result of tune_fair(training_set(1), 300), recorded (`weedspray-lab experiment step
// --plants N --tune` reruns it). Controller output u in [0, 1] closes the return valve.
FuzzyPidConfig fair_tuned_pid_config();
FuzzyPidConfig fair_tuned_fuzzy_pid_config();

}  // namespace weedspray::lab::experiments
