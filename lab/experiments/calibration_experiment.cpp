// SPDX-License-Identifier: Apache-2.0
// The two calibrations on the simulated machine: the flow meter's pulses per litre from a catch
// test, and each nozzle's line q = A s + b from runs of that nozzle alone measured with the
// ONE line flow meter (the way a user does it on the real boom).
#include <algorithm>
#include <cmath>
#include <deque>
#include <mutex>
#include <random>
#include <utility>
#include <vector>

#include "lab/experiments/experiments.hpp"
#include "lab/experiments/vocabulary.hpp"

namespace weedspray::lab::experiments {
namespace {

RigConfig calibration_rig(const CalibrationOptions& options) {
  RigConfig config;
  config.seed = options.seed;
  config.setpoint_mpa = options.pressure_mpa;
  config.pwm_frequency_hz = options.frequency_hz;
  config.fixes = {true, false, false};
  config.record_period_s = 0.0;
  config.plant = options.plant;
  return config;
}

// The jug's reading error for this machine: its own stream of the machine's seed.
double catch_jug_error(const CalibrationOptions& options) {
  if (!(options.jug_error_limit > 0.0)) return 0.0;
  std::seed_seq seq{static_cast<std::uint32_t>(options.seed),
                    static_cast<std::uint32_t>(options.seed >> 32), 0x6a7567U};
  std::mt19937_64 rng(seq);
  return std::uniform_real_distribution<double>(-options.jug_error_limit,
                                                options.jug_error_limit)(rng);
}

}  // namespace

CalibrationResult run_calibration(const CalibrationOptions& options) {
  CalibrationResult result;
  RigConfig config = calibration_rig(options);
  ClosedLoopRig rig(config);
  const int n = rig.plant().nozzle_count();
  const double nominal = config.meter_pulses_per_l;
  if (options.change) apply_change(rig.plant(), *options.change);

  // Catch test: all nozzles open, liquid collected (the plant's true volume as the jug reads
  // it) vs pulses.
  rig.command_duties(std::vector<double>(static_cast<std::size_t>(n), 100.0));
  rig.start();
  rig.run_for(options.settle_s);
  const double litres0 = rig.plant().total_delivered_l();
  const std::uint64_t pulses0 = rig.plant().flow_meter_pulses();
  rig.run_for(options.catch_test_s);
  const double jug_error = catch_jug_error(options);
  result.jug_error_pct = jug_error * 100.0;
  result.meter = calibrate_flow_meter(
      rig.plant().flow_meter_pulses() - pulses0,
      (rig.plant().total_delivered_l() - litres0) * (1.0 + jug_error), nominal);
  result.true_pulses_per_litre = rig.plant().true_meter_pulses_per_l();
  result.meter_k_error_pct =
      (nominal - result.true_pulses_per_litre) / result.true_pulses_per_litre * 100.0;
  result.meter_calibration_error_pct =
      (result.meter.pulses_per_litre - result.true_pulses_per_litre) /
      result.true_pulses_per_litre * 100.0;

  // Nozzle lines: each nozzle alone at each duty, pressure held by the loop.
  for (int nozzle = 0; nozzle < n; ++nozzle) {
    // This nozzle alone at `duty`: the flow by the calibrated meter and the plant's true flow.
    const auto measure = [&](double duty) {
      std::vector<double> duties(static_cast<std::size_t>(n), 0.0);
      duties[static_cast<std::size_t>(nozzle)] = duty;
      rig.command_duties(duties);
      rig.run_for(options.settle_s);
      const double v0 = rig.plant().nozzle_delivered_l(nozzle);
      const std::uint64_t p0 = rig.plant().flow_meter_pulses();
      rig.run_for(options.measure_s);
      const double minutes = options.measure_s / 60.0;
      const double pulses = static_cast<double>(rig.plant().flow_meter_pulses() - p0);
      return std::pair{
          DutyFlowPoint{duty, pulses / result.meter.pulses_per_litre / minutes},
          DutyFlowPoint{duty, (rig.plant().nozzle_delivered_l(nozzle) - v0) / minutes}};
    };
    std::vector<DutyFlowPoint> metered;
    std::vector<DutyFlowPoint> truth;
    for (double duty : options.duties_pct) {
      const auto [by_meter, true_flow] = measure(duty);
      metered.push_back(by_meter);
      truth.push_back(true_flow);
    }
    const auto [full_open, true_full_open] = measure(100.0);
    const double lo = options.duties_pct.front();
    const double hi = options.duties_pct.back();
    NozzleCalibration cal;
    const NozzleLineFit fit = fit_nozzle_line(metered, options.pressure_mpa, lo, hi);
    cal.fitted = fit.line;
    cal.r_squared = fit.r_squared;
    cal.truth = fit_nozzle_line(truth, options.pressure_mpa, lo, hi).line;
    cal.full_open_l_per_min = full_open.flow_l_per_min;
    cal.true_full_open_l_per_min = true_full_open.flow_l_per_min;
    result.nozzles.push_back(cal);
  }
  return result;
}

const CalibrationResult& cached_calibration(const CalibrationOptions& options) {
  auto same = [](const CalibrationOptions& a, const CalibrationOptions& b) {
    return a.seed == b.seed && a.pressure_mpa == b.pressure_mpa &&
           a.frequency_hz == b.frequency_hz && a.catch_test_s == b.catch_test_s &&
           a.duties_pct == b.duties_pct && a.settle_s == b.settle_s && a.measure_s == b.measure_s &&
           a.plant == b.plant && a.change == b.change && a.jug_error_limit == b.jug_error_limit;
  };
  static std::mutex mutex;
  // deque: references handed out stay valid as entries are added.
  static std::deque<std::pair<CalibrationOptions, CalibrationResult>> cache;
  const std::lock_guard lock(mutex);
  for (const auto& [key, result] : cache)
    if (same(key, options)) return result;
  cache.emplace_back(options, run_calibration(options));
  return cache.back().second;
}

CalibrationFleetResult run_calibration_fleet(const FleetOptions& fleet,
                                             const CalibrationOptions& base) {
  std::vector<double> meter, full, line, r2;
  for (const Machine& m : draw_machines(fleet.seed, fleet.plants)) {
    CalibrationOptions options = base;
    options.seed = m.seed;
    options.plant = m.params;
    const CalibrationResult r = run_calibration(options);
    meter.push_back(std::abs(r.meter_calibration_error_pct));
    double worst_full = 0.0, worst_line = 0.0, lowest_r2 = 1.0;
    for (const auto& n : r.nozzles) {
      worst_full = std::max(
          worst_full, std::abs(n.full_open_l_per_min / n.true_full_open_l_per_min - 1.0) * 100.0);
      for (double duty : {20.0, 50.0, 80.0}) {
        const double fitted =
            n.fitted.slope_l_per_min_per_pct * duty + n.fitted.intercept_l_per_min;
        const double truth = n.truth.slope_l_per_min_per_pct * duty + n.truth.intercept_l_per_min;
        worst_line = std::max(worst_line, std::abs(fitted / truth - 1.0) * 100.0);
      }
      lowest_r2 = std::min(lowest_r2, n.r_squared);
    }
    full.push_back(worst_full);
    line.push_back(worst_line);
    r2.push_back(lowest_r2);
  }
  return {spread_of(meter), spread_of(full), spread_of(line), spread_of(r2, true)};
}

CalibratedMachine calibrate_as_made(std::uint64_t seed, const plant::PlantParams& plant,
                                    double pressure_mpa, double frequency_hz) {
  CalibrationOptions cal_options;
  cal_options.seed = seed;
  cal_options.pressure_mpa = pressure_mpa;
  cal_options.frequency_hz = frequency_hz;
  cal_options.plant = plant;
  const CalibrationResult& cal = cached_calibration(cal_options);
  CalibratedMachine m;
  m.config.plant = plant;
  m.config.seed = seed;
  m.config.setpoint_mpa = pressure_mpa;
  m.config.pwm_frequency_hz = frequency_hz;
  m.config.record_period_s = 0.0;
  m.config.meter_pulses_per_l = cal.meter.pulses_per_litre;
  for (const auto& n : cal.nozzles) m.lines.push_back(n.fitted);
  m.full_flows = calibrated_full_flows(cal);
  return m;
}

ClosedLoopRig calibrated_rig(const CalibratedMachine& m) {
  ClosedLoopRig rig(m.config);
  rig.set_nozzle_lines(m.lines);
  rig.set_full_open_flows(m.full_flows);
  return rig;
}

std::vector<double> calibrated_full_flows(const CalibrationResult& calibration) {
  std::vector<double> flows;
  for (const auto& n : calibration.nozzles) flows.push_back(n.full_open_l_per_min);
  return flows;
}

}  // namespace weedspray::lab::experiments
