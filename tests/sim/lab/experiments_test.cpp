// SPDX-License-Identifier: Apache-2.0
// The papers' experiments on the simulated machine, asserting the figures the project
// promises (brief: plant engineer). Volumes are judged against the plant's TRUE volumes.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <random>
#include <stdexcept>
#include <vector>

#include "lab/experiments/experiments.hpp"
#include "lab/experiments/vocabulary.hpp"

namespace weedspray::lab::experiments {
namespace {

TEST(StepExperiment, FuzzyPidMeetsTheStartUpTargetsAndBeatsTheTunedPid) {
  const StepResult r = run_step(StepOptions{});
  EXPECT_LE(r.fuzzy_pid.metrics.overshoot_pct, 5.0);
  EXPECT_TRUE(r.fuzzy_pid.metrics.settled);
  EXPECT_LE(r.fuzzy_pid.metrics.settle_s, 1.0);
  EXPECT_LT(r.fuzzy_pid.metrics.itae, r.pid.metrics.itae);
  EXPECT_TRUE(r.pid.metrics.settled);  // the comparison is against a working PID
}

TEST(StepExperiment, FuzzyPidStillSettlesOnAnotherPlantSeed) {
  StepOptions options;
  options.seed = 42;
  const StepResult r = run_step(options);
  EXPECT_LE(r.fuzzy_pid.metrics.overshoot_pct, 5.0);
  EXPECT_LE(r.fuzzy_pid.metrics.settle_s, 1.0);
}

// The daemon runs the loop at 100 Hz with the converters on their own thread: the ADC is read
// `lead_s` ahead of each tick and the DAC written 1 ms after it.
StepOptions daemon_timing(double lead_s) {
  StepOptions options;
  options.control_period_s = 0.010;
  options.converter_lead_s = lead_s;
  options.converter_lag_s = 0.001;
  return options;
}

// An ADS1115 read (~1.5 ms) makes the worker's lead 1.5 x 1.5 + 0.3 = ~2.5 ms: the start-up
// targets still hold there.
TEST(StepExperiment, TargetsHoldWithTheDaemonsLoopRateAndAnIioConverter) {
  const StepResult r = run_step(daemon_timing(0.0025));
  EXPECT_LE(r.fuzzy_pid.metrics.overshoot_pct, 5.0);
  EXPECT_TRUE(r.fuzzy_pid.metrics.settled);
  EXPECT_LE(r.fuzzy_pid.metrics.settle_s, 1.0);
  EXPECT_LT(r.fuzzy_pid.metrics.itae, r.pid.metrics.itae);
}

// A Modbus module at 115200 baud pushes the lead to its cap, half a period (5 ms): no overshoot
// beyond 5 % and settled within the record, but slower (README: 1.36 s), and more dead time
// costs accuracy against the IIO converter's timing.
TEST(StepExperiment, ASlowConverterAtHalfAPeriodStillSettles) {
  const StepResult slow = run_step(daemon_timing(0.005));
  EXPECT_LE(slow.fuzzy_pid.metrics.overshoot_pct, 5.0);
  EXPECT_TRUE(slow.fuzzy_pid.metrics.settled);
  EXPECT_TRUE(slow.pid.metrics.settled);
  EXPECT_GT(slow.fuzzy_pid.metrics.itae, run_step(daemon_timing(0.0025)).fuzzy_pid.metrics.itae);
  // A lead of a whole period is not a schedule.
  EXPECT_THROW((void)run_step(daemon_timing(0.010)), std::invalid_argument);
}

TEST(RippleExperiment, StaggeredSwitchingSwingsThePressureFarLess) {
  const RippleResult r = run_ripple(RippleOptions{});
  EXPECT_GT(r.synchronous.pp_mpa, 0.01);
  EXPECT_LT(r.staggered.pp_mpa * 4.0, r.synchronous.pp_mpa);
}

TEST(CalibrationExperiment, FindsTheMeterErrorAndTheTrueNozzleLines) {
  CalibrationOptions exact_jug;
  exact_jug.jug_error_limit = 0.0;
  const CalibrationResult r = run_calibration(exact_jug);
  // The label (8500) is off by the plant's K-factor error; the catch test finds the truth.
  EXPECT_GT(std::abs(r.meter_k_error_pct), 1.0);
  EXPECT_LT(std::abs(r.meter_calibration_error_pct), 0.1);
  EXPECT_EQ(r.jug_error_pct, 0.0);
  ASSERT_EQ(r.nozzles.size(), 4u);
  for (const auto& n : r.nozzles) {
    EXPECT_NEAR(n.fitted.slope_l_per_min_per_pct, n.truth.slope_l_per_min_per_pct,
                0.01 * n.truth.slope_l_per_min_per_pct);
    EXPECT_NEAR(n.fitted.intercept_l_per_min, n.truth.intercept_l_per_min, 0.003);
    EXPECT_GT(n.r_squared, 0.999);
  }
}

// The catch test reads its volume off a jug: the meter's K comes out off by the jug's drawn
// error (the meter reads high by what the jug reads low), within its +-0.8 %.
TEST(CalibrationExperiment, TheMeterCarriesTheCatchJugsReadingError) {
  const CalibrationResult r = run_calibration(CalibrationOptions{});
  EXPECT_NE(r.jug_error_pct, 0.0);
  EXPECT_LE(std::abs(r.jug_error_pct), 0.8);
  EXPECT_NEAR(r.meter_calibration_error_pct, -r.jug_error_pct, 0.1);
}

TEST(LinearityExperiment, CalibratedMachineIsLinearAndRawIsNot) {
  const LinearityResult fixed = run_linearity(SprayRunOptions{});
  EXPECT_GE(fixed.r2, 0.999);
  EXPECT_LE(fixed.mean_error_pct, 1.0);
  EXPECT_LE(fixed.max_error_pct, 2.0);
  SprayRunOptions raw_options;
  raw_options.raw = true;
  const LinearityResult raw = run_linearity(raw_options);
  EXPECT_GT(raw.mean_error_pct, 3.0 * fixed.mean_error_pct);
  EXPECT_GT(raw.max_error_pct, 10.0);  // valve delays at low duty (UGV paper: up to 12 %)
}

TEST(OrthogonalExperiment, MeetsTheVolumeAndPressureTargets) {
  const OrthogonalResult r = run_orthogonal(SprayRunOptions{});
  ASSERT_EQ(r.runs.size(), 16u);
  EXPECT_LE(r.mean_error_pct, 1.0);
  EXPECT_LE(r.max_error_pct, 2.0);
  EXPECT_LE(r.pressure_band_mpa, 0.01);
}

TEST(OrthogonalExperiment, RawMachineShowsThePapersLargeErrors) {
  SprayRunOptions options;
  options.raw = true;
  const OrthogonalResult r = run_orthogonal(options);
  EXPECT_GT(r.mean_error_pct, 3.0);
  EXPECT_GT(r.max_error_pct, 8.0);
  // The worst errors are at 25 % duty, as in the paper.
  double worst_duty = 0, worst = 0;
  for (const auto& run : r.runs)
    for (const auto& n : run.nozzles)
      if (n.error_pct > worst) worst = n.error_pct, worst_duty = n.duty_pct;
  EXPECT_EQ(worst_duty, 25.0);
}

TEST(DoseExperiment, DeliveredFlowTracksTheTheoreticalFlow) {
  const DoseResult r = run_dose(DoseOptions{});
  ASSERT_EQ(r.points.size(), 8u);
  EXPECT_GE(r.r2, 0.968);  // the wheat paper's field figure
  EXPECT_LT(r.mean_error_pct, 2.0);
  EXPECT_NEAR(r.points.front().theoretical_l_per_min, 0.328, 0.001);
  EXPECT_NEAR(r.points.back().theoretical_l_per_min, 0.615, 0.001);
}

TEST(SavingsExperiment, VariableSprayingSavesLiquidOnASparseField) {
  // Seeded synthetic field, most zones sparse: variable must use clearly less liquid.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 0.75);
  std::vector<std::array<double, 4>> zones(40);
  for (auto& z : zones)
    for (auto& d : z) d = u(rng) * u(rng) / 0.75 + 0.2;
  const SavingsResult r = run_savings(zones, SavingsOptions{});
  EXPECT_GT(r.savings_pct, 20.0);
  EXPECT_LT(r.savings_pct, 90.0);
  EXPECT_LT(r.under_dosed_zones, r.zones / 4);
  // Equal coverage leaves no weedy zone dry; the SPEC clamp does on this sparse field, and
  // saves more liquid by doing so.
  EXPECT_EQ(r.unsprayed_weedy_zones, 0);
  EXPECT_EQ(r.equal_coverage.unsprayed_weedy_zones, 0);
  EXPECT_GT(r.spec_clamp.unsprayed_weedy_zones, 0);
  EXPECT_GT(r.spec_clamp.savings_pct, r.savings_pct);
  EXPECT_EQ(r.zone_delivered_l.size(), zones.size());
  // All-dense field: nothing to save.
  const std::vector<std::array<double, 4>> dense(10, {0.75, 0.75, 0.75, 0.75});
  EXPECT_NEAR(run_savings(dense, SavingsOptions{}).savings_pct, 0.0, 2.0);
}

// A labelled field: weedy zones (crop and weed), crop-only zones, bare zones, and zones with a
// trace of weed under the decision threshold. Ground-truth weed density sprays every weedy
// zone and no crop-only one; acting on all vegetation (crop + weed) sprays the crop too.
TEST(SavingsExperiment, TallyAgainstLabelledWeeds) {
  std::vector<std::array<ZoneTruth, 4>> truth;
  for (int z = 0; z < 24; ++z) {
    truth.push_back({ZoneTruth{0.04, 0.10},    // weedy, with crop
                     ZoneTruth{0.00, 0.15},    // crop only
                     ZoneTruth{0.007, 0.00},   // weedy, but under a 1 % decision threshold
                     ZoneTruth{0.00, 0.00}});  // bare soil
  }
  auto densities = [&](bool with_crop) {
    std::vector<std::array<double, 4>> zones(truth.size());
    for (std::size_t z = 0; z < truth.size(); ++z) {
      for (std::size_t n = 0; n < 4; ++n) {
        zones[z][n] = truth[z][n].weed + (with_crop ? truth[z][n].crop : 0.0);
      }
    }
    return zones;
  };
  SavingsOptions options;
  options.max_density = 1.0;
  options.decision_threshold = 0.005;
  const SavingsResult weeds = run_savings(densities(false), options);
  const TruthTally on_weeds = tally_against_truth(weeds.equal_coverage, truth);
  EXPECT_EQ(on_weeds.weedy_zones, 48);
  EXPECT_EQ(on_weeds.crop_only_zones, 24);
  EXPECT_EQ(on_weeds.weedy_left_dry, 0);
  EXPECT_EQ(on_weeds.crop_only_sprayed, 0);

  const SavingsResult green = run_savings(densities(true), options);
  const TruthTally on_green = tally_against_truth(green.equal_coverage, truth);
  EXPECT_EQ(on_green.weedy_left_dry, 0);
  EXPECT_EQ(on_green.crop_only_sprayed, 24);
  // Every sprayed zone is at the minimum duty here: the crop column adds half again.
  EXPECT_GT(green.variable_l, 1.4 * weeds.variable_l);
  EXPECT_GT(weeds.savings_pct, green.savings_pct);

  // The daemon's 1 % threshold leaves the 0.7 % zones dry, the SPEC clamp every weedy zone
  // whose duty falls under 20 %.
  options.decision_threshold = 0.01;
  const SavingsResult strict = run_savings(densities(false), options);
  EXPECT_EQ(tally_against_truth(strict.equal_coverage, truth).weedy_left_dry, 24);
  EXPECT_EQ(tally_against_truth(strict.spec_clamp, truth).weedy_left_dry, 48);

  truth.pop_back();
  EXPECT_THROW(tally_against_truth(weeds.equal_coverage, truth), std::invalid_argument);
}

// A rate controller's target follows the ground speed: the runs' duties are the demand at the
// reference speed (1 m/s), and a step to another speed after the calibration moves every asked
// volume by the speed ratio, up to the full-open flow (the rest clipped and reported).
MachineChange speed_step_to(double speed_m_per_s) {
  MachineChange change;
  change.valve_ageing.fill(1.0);
  change.supply_volts_start = change.supply_volts_end = plant::PlantParams{}.pump.supply_volts;
  change.speed_start_m_per_s = change.speed_end_m_per_s = speed_m_per_s;
  return change;
}

TEST(SpeedFollowingTarget, AStepInGroundSpeedMovesTheAskedVolumeByTheSpeedRatio) {
  SprayRunOptions options;
  options.run_s = 10.0;
  const LinearityResult reference = run_linearity(options);
  options.change = speed_step_to(0.8);
  const LinearityResult slower = run_linearity(options);
  options.change = speed_step_to(1.2);
  const LinearityResult faster = run_linearity(options);
  ASSERT_EQ(slower.points.size(), reference.points.size());
  ASSERT_EQ(faster.points.size(), reference.points.size());
  for (std::size_t i = 0; i < reference.points.size(); ++i) {
    const DutyPoint& ref = reference.points[i];
    const DutyPoint& slow = slower.points[i];
    const DutyPoint& fast = faster.points[i];
    SCOPED_TRACE(ref.duty_pct);
    EXPECT_EQ(ref.clipped_l, 0.0);
    EXPECT_NEAR(slow.requested_l / ref.requested_l, 0.8, 1e-9);
    EXPECT_EQ(slow.clipped_l, 0.0);
    // The controller follows the lower target; at 10 % x 0.8 the pulse (about 4 % duty at 3 Hz)
    // is shorter than the valve opens and closes in.
    if (ref.duty_pct >= 20.0) {
      EXPECT_LE(slow.error_pct, 2.0);
    }
    if (1.2 * ref.duty_pct <= 100.0) {
      EXPECT_NEAR(fast.requested_l / ref.requested_l, 1.2, 1e-9);
      EXPECT_EQ(fast.clipped_l, 0.0);
      EXPECT_LE(fast.error_pct, 2.0);
    } else {
      // Past the full-open flow: that is asked (held open), the rest clipped.
      const double full_l = ref.requested_l / (ref.duty_pct / 100.0);
      EXPECT_NEAR(fast.requested_l / full_l, 1.0, 1e-9);
      EXPECT_NEAR(fast.clipped_l / full_l, 1.2 * ref.duty_pct / 100.0 - 1.0, 1e-9);
    }
  }
}

TEST(SpeedFollowingTarget, TheDoseChecksTheoreticalFlowFollowsTheSpeed) {
  DoseOptions options;
  options.densities = {0.5, 0.75};
  options.run_s = 10.0;
  options.change = speed_step_to(1.2);
  const DoseResult r = run_dose(options);
  ASSERT_EQ(r.points.size(), 2U);
  EXPECT_NEAR(r.points[0].theoretical_l_per_min, 1.2 * 0.41, 1e-6);
  EXPECT_NEAR(r.points[1].theoretical_l_per_min, 1.2 * 0.615, 1e-6);
  for (const DosePoint& p : r.points) {
    EXPECT_EQ(p.clipped_l_per_min, 0.0);
    EXPECT_LT(std::abs(p.delivered_l_per_min / p.theoretical_l_per_min - 1.0), 0.02);
  }
}

}  // namespace
}  // namespace weedspray::lab::experiments
