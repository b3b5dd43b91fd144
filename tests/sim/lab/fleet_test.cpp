// SPDX-License-Identifier: Apache-2.0
// Experiments over drawn machines (the draws themselves: tests/sim/plant/machine_draw_test.cpp):
// the spread figure, the online flow trim after a change, staggered PWM with a pulsing pump, and
// the fairly tuned controllers on machines they were not tuned on. Each test would fail with the
// fix it covers switched off (trim disabled, stagger off, fuzzy corrections zeroed).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "lab/experiments/experiments.hpp"
#include "lab/experiments/fair_tuning.hpp"
#include "lab/experiments/vocabulary.hpp"

namespace weedspray::lab::experiments {
namespace {

TEST(Machines, SpreadIsMeanSampleSdAndWorst) {
  const std::vector<double> v{1.0, 2.0, 3.0, 6.0};
  const Spread s = spread_of(v);
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_NEAR(s.sd, std::sqrt(14.0 / 3.0), 1e-12);
  EXPECT_DOUBLE_EQ(s.worst, 6.0);
  EXPECT_DOUBLE_EQ(spread_of(v, true).worst, 1.0);
  EXPECT_EQ(s.count, 4);
}

// One machine calibrated as made, then all its nozzles worn 4 % and its meter unchanged: a
// common-mode change the trim, reading the calibrated meter, can see and take out of the
// nozzles it modulates. A nozzle held open (100 %) is out of any trim's reach (it sprays its
// worn full flow), so the whole-run mean is judged on the modulated nozzles (duty below 100 %).
double modulated_mean_error_pct(const OrthogonalResult& r) {
  double sum = 0.0;
  int count = 0;
  for (const auto& run : r.runs) {
    for (const auto& p : run.nozzles) {
      if (p.duty_pct >= 100.0) continue;
      sum += p.error_pct;
      ++count;
    }
  }
  return count > 0 ? sum / count : 0.0;
}

TEST(FleetOrthogonal, OnlineTrimTakesOutAChangeAfterCalibration) {
  const Machine m = draw_machine(1, 0);
  SprayRunOptions options;
  options.seed = m.seed;
  options.plant = m.params;
  options.run_s = 12.0;
  MachineChange worn = no_change(m);
  worn.nozzle_wear.fill(0.04);
  options.change = worn;
  options.flow_feedback = true;
  const OrthogonalResult on = run_orthogonal(options);
  options.flow_feedback = false;
  const OrthogonalResult off = run_orthogonal(options);
  EXPECT_GT(modulated_mean_error_pct(off), 3.0);  // the wear shows without the trim
  EXPECT_LT(modulated_mean_error_pct(on), 0.5 * modulated_mean_error_pct(off));
  EXPECT_LT(on.mean_error_pct, off.mean_error_pct);
  EXPECT_LT(on.pressure_band_mpa, 0.02);
}

// The two halves of a drawn change add up to it, and neither carries the other's part.
TEST(Machines, ChangePartsSplitTheDrawnChange) {
  const Machine m = draw_machine(1, 3);
  const MachineChange all = draw_change(m, 1, 3);
  EXPECT_EQ(draw_change_parts(m, 1, 3, ChangeParts::kAll), all);
  EXPECT_EQ(draw_change_parts(m, 1, 3, ChangeParts::kNone), no_change(m));
  const MachineChange common = draw_change_parts(m, 1, 3, ChangeParts::kCommon);
  const MachineChange nozzle = draw_change_parts(m, 1, 3, ChangeParts::kPerNozzle);
  EXPECT_EQ(common.nozzle_wear, no_change(m).nozzle_wear);
  EXPECT_EQ(common.valve_ageing, no_change(m).valve_ageing);
  EXPECT_EQ(common.blockage, 0.0);
  EXPECT_EQ(common.meter_drift, all.meter_drift);
  EXPECT_EQ(common.supply_volts_end, all.supply_volts_end);
  EXPECT_EQ(common.speed_end_m_per_s, all.speed_end_m_per_s);
  EXPECT_EQ(nozzle.nozzle_wear, all.nozzle_wear);
  EXPECT_EQ(nozzle.valve_ageing, all.valve_ageing);
  EXPECT_EQ(nozzle.blocked_nozzle, all.blocked_nozzle);
  EXPECT_EQ(nozzle.blockage, all.blockage);
  EXPECT_EQ(nozzle.meter_drift, 0.0);
  EXPECT_EQ(nozzle.supply_volts_end, nozzle.supply_volts_start);
  EXPECT_NE(all.meter_drift, 0.0);
  EXPECT_GT(all.blockage, 0.0);
}

// One nozzle's own change, which no boom trim can see from the one meter: recalibrating the
// changed machine (what `sprayctl calibrate nozzles` does) finds it; the trim alone does not.
TEST(FleetOrthogonal, RecalibratingAfterTheChangeFindsOneNozzlesOwnChange) {
  const Machine m = draw_machine(1, 0);
  MachineChange blocked = no_change(m);
  blocked.blocked_nozzle = 1;
  blocked.blockage = 0.08;
  CalibrationOptions cal;
  cal.seed = m.seed;
  cal.plant = m.params;
  // The cache: the runs below calibrate with these same options (a calibration is ~12 simulated
  // minutes, the long pole of this file under qemu).
  const double as_made = cached_calibration(cal).nozzles[1].full_open_l_per_min;
  cal.change = blocked;
  const double after = cached_calibration(cal).nozzles[1].full_open_l_per_min;
  EXPECT_NEAR(after / as_made, 0.92, 0.01);

  SprayRunOptions options;
  options.seed = m.seed;
  options.plant = m.params;
  options.run_s = 6.0;
  options.change = blocked;
  const OrthogonalResult trimmed = run_orthogonal(options);
  options.recalibrated = true;
  const OrthogonalResult recalibrated = run_orthogonal(options);
  EXPECT_GT(trimmed.max_error_modulated_pct, 5.0);  // the blocked nozzle trimmed as a boom
  // Against the target as made, the blocked nozzle asked for its full flow stays held open and
  // short by its blockage whatever the calibration (the held-open floor): the recalibration's
  // worth is in the modulated runs.
  EXPECT_LT(recalibrated.max_error_modulated_pct, 0.6 * trimmed.max_error_modulated_pct);
  EXPECT_LT(recalibrated.mean_error_pct, trimmed.mean_error_pct);
  std::printf("trimmed %.2f / %.2f %%, recalibrated %.2f / %.2f %% (mean / max below 100 %%)\n",
              trimmed.mean_error_pct, trimmed.max_error_modulated_pct, recalibrated.mean_error_pct,
              recalibrated.max_error_modulated_pct);
}

// The first drawn machine as made, and the same with one nozzle 8 % blocked.
SprayRunOptions first_machine(bool blocked) {
  const Machine m = draw_machine(1, 0);
  SprayRunOptions options;
  options.seed = m.seed;
  options.plant = m.params;
  options.change = no_change(m);
  if (blocked) {
    options.change->blocked_nozzle = 1;
    options.change->blockage = 0.08;
  }
  return options;
}

// One nozzle's own change (8 % blocked; another 4 % worn) found without the user: the headland
// re-check holds each nozzle open alone, reads it against its calibrated held-open flow and
// rescales its line, so the modulated runs ask the changed nozzle for the duty that gives its
// share. Without the rescale the row is the trim alone (the blocked nozzle trimmed as one of a
// boom).
TEST(FleetOrthogonal, HeadlandRecheckFindsOneNozzlesOwnChange) {
  SprayRunOptions options = first_machine(true);
  options.run_s = 10.0;
  options.change->nozzle_wear[2] = 0.04;
  const OrthogonalResult trimmed = run_orthogonal(options);
  options.headland_recheck = true;
  const OrthogonalResult rechecked = run_orthogonal(options);
  std::printf("trimmed %.2f / %.2f %%, re-checked %.2f / %.2f %% (mean / max below 100 %%)\n",
              trimmed.mean_error_pct, trimmed.max_error_modulated_pct, rechecked.mean_error_pct,
              rechecked.max_error_modulated_pct);
  EXPECT_GT(trimmed.max_error_modulated_pct, 4.0);
  EXPECT_LT(rechecked.max_error_modulated_pct, 0.6 * trimmed.max_error_modulated_pct);
  EXPECT_LT(rechecked.mean_error_pct, 0.6 * trimmed.mean_error_pct);
}

// The held-open floor prices one nozzle's own change from the plant's truth: nothing on the
// machine as made; with one nozzle 8 % blocked, the L16 runs that hold it open beside healthy
// nozzles cost any controller that keeps them open about half of it (the pressure balances the
// high against the low). Counting the flows as made instead of with the blockage gives ~0.
TEST(FleetOrthogonal, HeldOpenFloorPricesOneNozzlesOwnChange) {
  EXPECT_LT(orthogonal_held_open_floor_pct(first_machine(false)), 0.5);
  const double floor_pct = orthogonal_held_open_floor_pct(first_machine(true));
  EXPECT_GT(floor_pct, 3.0);
  EXPECT_LT(floor_pct, 5.0);
}

// The boom-wide floor of the mean error prices what one meter cannot see: nothing as made; a
// 1 % meter drift alone costs every nozzle about 1 % (the law believes its meter; ignoring the
// drift gives ~0); one nozzle 8 % blocked costs about a quarter of that where it sprays beside
// three healthy ones (one common factor cannot single it out).
TEST(FleetOrthogonal, CommonFloorPricesTheMeterDriftAndOneNozzlesChange) {
  SprayRunOptions options = first_machine(false);
  EXPECT_LT(orthogonal_common_floor_pct(options), 0.3);
  options.change->meter_drift = 0.01;
  EXPECT_NEAR(orthogonal_common_floor_pct(options), 1.0, 0.3);
  const double floor_pct = orthogonal_common_floor_pct(first_machine(true));
  EXPECT_GT(floor_pct, 1.0);
  EXPECT_LT(floor_pct, 3.0);
}

TEST(FleetRipple, StaggeringCutsThePressureSwingOnEveryMachine) {
  RippleOptions base;
  base.settle_s = 2.0;
  base.measure_s = 2.0;
  const RippleFleetResult r = run_ripple_fleet({5, 3, false}, base);
  EXPECT_GT(r.ratio.worst, 4.0);  // manifold (sensor)
  EXPECT_LT(r.staggered_boom_pp_mpa.worst, 0.5 * r.synchronous_boom_pp_mpa.mean);
  // The pump's pulsation alone moves the staggered line a little, never to zero.
  EXPECT_GT(r.staggered_pp_mpa.mean, 0.0);
}

// One drawn machine, trim on: a minute healthy without an alarm, then a nozzle 20 % blocked is
// named (the right one) within 10 s.
// The dose check over drawn machines: each calibrated as made, then changed; the trim's worth
// shows on every machine, and the delivered flow stays a straight line of the theoretical one.
TEST(FleetDose, OnEveryMachineTheTrimKeepsTheDoseLine) {
  DoseOptions base;
  base.densities = {0.40, 0.55, 0.75};
  base.run_s = 15.0;
  const DoseFleetResult r = run_dose_fleet({1, 2, true}, base);
  std::printf("dose, 2 machines: trim on mean %.2f %% (worst max %.2f %%), off %.2f %% (%.2f %%)\n",
              r.trim_on.mean_error_pct.mean, r.trim_on.max_error_pct.worst,
              r.trim_off.mean_error_pct.mean, r.trim_off.max_error_pct.worst);
  EXPECT_EQ(r.trim_on.mean_error_pct.count, 2);
  EXPECT_LT(r.trim_on.mean_error_pct.mean, 0.6 * r.trim_off.mean_error_pct.mean);
  EXPECT_LT(r.trim_on.max_error_pct.worst, r.trim_off.max_error_pct.worst);
  EXPECT_GT(r.trim_on.r2.worst, 0.999);
}

// The boom-total dose over a field (speed swing, patches, a headland) on drawn machines, each
// calibrated as made, then changed (wear, valve ageing, meter drift, supply ramp): within 2 %
// of the requested L/ha with the trim on, and on every machine further off with it off.
TEST(FleetFieldDose, TheTrimKeepsTheBoomTotalDoseWithinTwoPercent) {
  FieldDoseOptions options;
  options.run_s = 120.0;  // one headland (105-120 s) and a share of the speed swing
  const FieldDoseFleetResult r = run_field_dose_fleet({1, 3, true}, options);
  ASSERT_EQ(r.machines.size(), 3U);
  for (const FieldDoseMachine& m : r.machines) {
    std::printf("field dose: trim on %+.2f %%, off %+.2f %% (drift %+.2f %%, raised %.1f %%)\n",
                m.trim_on.error_pct, m.trim_off.error_pct, m.change.meter_drift * 100.0,
                m.trim_on.raised_share_pct);
    EXPECT_LE(std::abs(m.trim_on.error_pct), 2.0);
    EXPECT_GT(std::abs(m.trim_off.error_pct), std::abs(m.trim_on.error_pct) + 1.0);
    EXPECT_GT(m.trim_on.area_ha, 0.0);
    EXPECT_NEAR(m.trim_on.target_l_per_ha, m.trim_off.target_l_per_ha, 1e-9);  // one field
  }
  EXPECT_LE(r.trim_on.abs_error_pct.worst, 2.0);
  EXPECT_GT(r.trim_off.abs_error_pct.mean, 2.0 * r.trim_on.abs_error_pct.mean);
}

TEST(FleetBlockage, ABlockedNozzleIsNamedAndAHealthyMinuteIsQuiet) {
  BlockageOptions options;
  options.healthy_s = 60.0;
  // The detector on the duties that separate the nozzles best: on field-like ones this
  // machine's blocked nozzle is not named within the limit.
  options.duties = BlockageDuties::kIid;
  options.recheck = false;
  const BlockageFleetResult r = run_blockage_fleet({1, 1, false}, options);
  ASSERT_EQ(r.machines.size(), 1U);
  EXPECT_FALSE(r.machines[0].false_alarm);
  // The healthy scatter of the shown ratios and the detector's evidence are measured (a real
  // estimate never sits exactly on its baseline) and, with no false alarm, the evidence stayed
  // below the alarm threshold.
  EXPECT_GT(r.machines[0].healthy_worst_deviation, 0.0);
  EXPECT_EQ(r.healthy_worst_deviation.count, 1);
  EXPECT_GT(r.machines[0].healthy_max_evidence, 0.0);
  EXPECT_LT(r.machines[0].healthy_max_evidence, options.health.alarm_threshold);
  EXPECT_EQ(r.healthy_max_evidence.count, 1);
  EXPECT_EQ(r.machines[0].named_nozzle, r.machines[0].blocked_nozzle);
  EXPECT_EQ(r.named_within_limit, 1);
}

// The headland re-check on field duties (the default): each nozzle held open alone on the
// headlands and read against its calibration. A nozzle 10 % off is named by the end of the
// first headland after it happened, and the healthy part's re-check (the headland at
// 105-120 s) names nothing.
BlockageOptions recheck_options() {
  BlockageOptions options;
  EXPECT_TRUE(options.recheck);
  options.healthy_s = 150.0;
  options.blockage = 0.1;
  return options;
}

TEST(FleetBlockage, TheHeadlandReCheckNamesANozzleTenPercentOffByTheNextHeadland) {
  const BlockageOptions options = recheck_options();
  EXPECT_EQ(options.duties, BlockageDuties::kField);
  const BlockageFleetResult r = run_blockage_fleet({1, 2, false}, options);
  ASSERT_EQ(r.machines.size(), 2U);
  for (const BlockageMachine& m : r.machines) {
    std::printf(
        "blocked %d, named %d after %.2f s (limit %.1f s), reading %.3f, healthy "
        "re-checks %d, their largest |reading - 1| %.3f\n",
        m.blocked_nozzle, m.named_nozzle, m.detect_s, m.limit_s, m.blocked_ratio,
        m.healthy_rechecks, m.healthy_reading_deviation);
    EXPECT_FALSE(m.false_alarm);
    EXPECT_GE(m.healthy_rechecks, 1);
    EXPECT_LT(m.healthy_reading_deviation, 0.05);
    EXPECT_EQ(m.named_nozzle, m.blocked_nozzle);
    EXPECT_NEAR(m.blocked_ratio, 0.9, 0.03);
  }
  EXPECT_EQ(r.named_within_limit, 2);
}

// A nozzle already blocked when the job starts: the re-check reads it against its calibration
// and names it at the first headland; a judge that learns its baseline in the job (the passive
// CUSUM) takes the blockage for that nozzle's normal and names nothing.
TEST(FleetBlockage, ANozzleBlockedFromTheStartIsNamedAtTheFirstHeadland) {
  BlockageOptions options = recheck_options();
  options.blocked_at_start = true;
  const BlockageMachine m = run_blockage_fleet({1, 1, false}, options).machines.at(0);
  const double first_headland_end = options.field.headland_every_s;
  EXPECT_EQ(m.named_nozzle, m.blocked_nozzle);
  EXPECT_GT(m.detect_s, first_headland_end - options.field.headland_s);
  EXPECT_LE(m.detect_s, first_headland_end);
  options.recheck = false;
  const BlockageMachine passive = run_blockage_fleet({1, 1, false}, options).machines.at(0);
  EXPECT_NE(passive.named_nozzle, passive.blocked_nozzle);
}

// The duties the experiment sprays: field-like ones (the default) stay close from one second to
// the next and close nozzles (patches too thin to spray, the headland at 105-120 s); the
// i.i.d. redraw does neither. Both runs stop at the healthy part's end (no detection measured).
TEST(FleetBlockage, FieldDutiesAreCorrelatedAndCloseNozzlesIidDutiesNeither) {
  BlockageOptions options;
  EXPECT_EQ(options.duties, BlockageDuties::kField);
  options.healthy_s = 60.0;
  options.detect_limit_s = 0.0;
  const BlockageMachine field = run_blockage_fleet({1, 1, false}, options).machines.at(0);
  options.duties = BlockageDuties::kIid;
  options.recheck = false;
  const BlockageMachine iid = run_blockage_fleet({1, 1, false}, options).machines.at(0);
  std::printf("field: closed %.2f, lag-1 r %.2f; iid: closed %.2f, lag-1 r %.2f\n",
              field.closed_share, field.share_lag_correlation, iid.closed_share,
              iid.share_lag_correlation);
  EXPECT_GT(field.closed_share, 0.15);
  EXPECT_GT(field.share_lag_correlation, 0.6);
  EXPECT_EQ(iid.closed_share, 0.0);
  EXPECT_LT(std::abs(iid.share_lag_correlation), 0.2);
}

}  // namespace
}  // namespace weedspray::lab::experiments
