// SPDX-License-Identifier: Apache-2.0
// The lab's rig runs the daemon's control steps: a rule that lives only in a step
// (control::PressureLoopStep's over-pressure trip) acts in the rig, and a step's setting
// (control::FlowTrimStep's correction bounds) moves an experiment's figure; the valves get the
// duties of the daemon's duty step (control::NozzleCommandStep), quantiser included.
#include "lab/experiments/closed_loop_rig.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "lab/experiments/experiments.hpp"

namespace weedspray::lab::experiments {
namespace {

TEST(ClosedLoopRig, ThePressureStepsTripStopsThePumpAndHoldsTheValves) {
  RigConfig config;
  config.setpoint_mpa = 0.3;
  config.over_pressure_mpa = 0.2;  // below the set-point: the start-up trips the step
  ClosedLoopRig rig(config);
  rig.command_duties(std::vector<double>(4, 50.0));
  rig.start();
  rig.run_for(3.0);
  ASSERT_FALSE(rig.trace().empty());
  EXPECT_EQ(rig.trace().back().valve_mask, 0u);                   // the valves held closed
  EXPECT_DOUBLE_EQ(rig.trace().back().return_valve_volts, 10.0);  // the return valve open
  EXPECT_LT(rig.plant().pump_rpm(), 1.0);                         // the pump off
  EXPECT_LT(rig.plant().line_pressure_mpa(), 0.05);

  RigConfig normal = config;
  normal.over_pressure_mpa = 0.9;  // the daemon's default: no trip
  ClosedLoopRig running(normal);
  running.command_duties(std::vector<double>(4, 50.0));
  running.start();
  running.run_for(3.0);
  EXPECT_GT(running.plant().pump_rpm(), 100.0);
  EXPECT_NEAR(running.plant().line_pressure_mpa(), 0.3, 0.02);
}

TEST(ClosedLoopRig, TheFlowTrimStepsSettingsMoveTheOrthogonalFigure) {
  // Every nozzle worn alike (+8 % flow): a change the boom's meter sees and the trim corrects.
  SprayRunOptions options;
  MachineChange change;
  change.nozzle_wear.fill(0.08);
  options.change = change;
  const OrthogonalResult trimmed = run_orthogonal(options);
  options.flow_trim.max_correction = 1.0;  // the step may not correct at all
  options.flow_trim.min_correction = 1.0;
  const OrthogonalResult pinned = run_orthogonal(options);
  // The wear ramps in over each measured run, so the trim takes out part of it (3.6 against
  // 4.7 % mean error when this was written).
  EXPECT_GT(pinned.mean_error_pct, trimmed.mean_error_pct + 0.5);
}

TEST(ClosedLoopRig, TheValvesGetTheDaemonsDutyStepWithItsQuantiser) {
  // A flow whose line duty lies between two of the daemon's default levels (20, 30, ... 80 %).
  const NozzleLine line;
  const double flow = line.slope_l_per_min_per_pct * 44.0 + line.intercept_l_per_min;
  const auto delivered = [&](bool quantise, double& duty) {
    RigConfig config;
    config.quantise = quantise;
    config.fixes.flow_feedback = false;
    config.fixes.pressure_compensation = false;
    config.record_period_s = 0.0;
    ClosedLoopRig rig(config);
    rig.request_flows(std::vector<double>(4, flow));
    rig.start();
    const auto volume_l = [&] {
      double sum = 0.0;
      for (int i = 0; i < 4; ++i) sum += rig.plant().nozzle_delivered_l(i);
      return sum;
    };
    rig.run_for(2.0);
    const double start_l = volume_l();
    rig.run_for(10.0);
    duty = rig.commanded_duties_pct()[0];
    return volume_l() - start_l;
  };
  double exact_duty = 0.0;
  double level_duty = 0.0;
  const double exact_l = delivered(false, exact_duty);
  const double level_l = delivered(true, level_duty);
  EXPECT_NEAR(exact_duty, 44.0, 1e-9);
  EXPECT_DOUBLE_EQ(level_duty, 40.0);
  // Four nozzles 4 % of duty apart for 10 s: about 0.01 L less.
  EXPECT_LT(level_l, exact_l - 0.005);
}

TEST(ClosedLoopRig, AFlowAboveTheBandIsSprayedByAlternatingPeriods) {
  // A calibrated machine asked for 96 % of each nozzle's metered held-open flow, the daemon's
  // band (20-80 %): no duty gives it, so whole periods alternate held open and 80 %.
  CalibrationOptions cal_options;
  cal_options.pressure_mpa = 0.2;
  cal_options.frequency_hz = 3.0;
  const CalibrationResult& cal = cached_calibration(cal_options);
  const std::vector<double> full = calibrated_full_flows(cal);
  std::vector<NozzleLine> lines;
  for (const auto& n : cal.nozzles) lines.push_back(n.fitted);
  std::vector<double> asked;
  for (const double f : full) asked.push_back(0.96 * f);
  const auto delivered_over_asked = [&](bool alternate) {
    RigConfig config;
    config.setpoint_mpa = 0.2;
    config.pwm_frequency_hz = 3.0;
    config.meter_pulses_per_l = cal.meter.pulses_per_litre;
    config.fixes.flow_feedback = false;
    config.duty_clamp = SprayLawConfig{};
    config.alternate_periods = alternate;
    config.record_period_s = 0.0;
    ClosedLoopRig rig(config);
    rig.set_nozzle_lines(lines);
    rig.set_full_open_flows(full);
    rig.request_flows(asked);
    rig.start();
    rig.run_for(3.0);
    double start_l = 0.0;
    for (int i = 0; i < 4; ++i) start_l += rig.plant().nozzle_delivered_l(i);
    rig.run_for(30.0);
    double litres = -start_l;
    for (int i = 0; i < 4; ++i) litres += rig.plant().nozzle_delivered_l(i);
    double asked_l = 0.0;
    for (const double q : asked) asked_l += q * 30.0 / 60.0;
    return litres / asked_l;
  };
  const double alternating = delivered_over_asked(true);
  const double held_open = delivered_over_asked(false);
  EXPECT_NEAR(alternating, 1.0, 0.015);
  EXPECT_GT(held_open, 1.03);  // held open: the nozzles' whole flow
}

}  // namespace
}  // namespace weedspray::lab::experiments
