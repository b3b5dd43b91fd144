// SPDX-License-Identifier: Apache-2.0
// The calibrations run from the daemon: the run's steps against a made-up boom and meter, and
// the stored results and which of them the rate law uses.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>

#include "daemon/records/calibration_store.hpp"
#include "daemon/sprayer/calibration_run.hpp"

namespace weedspray::daemon {
namespace {

namespace fs = std::filesystem;

// A boom of nozzles with their own true lines q = A s + b [L/min] while the valve's duty is s,
// and a meter of `k` pulses per litre counting their total: the run's duties in, pulses out.
struct MadeUpBoom {
  std::array<double, 3> slope{0.0080, 0.0056, 0.0088};
  std::array<double, 3> intercept{0.10, 0.07, 0.12};
  // Held open (100 %) a valve passes other than its pulsed line at 100 % (here more).
  std::array<double, 3> held_open_gain{1.06, 1.04, 1.08};
  double k = 8670.0;
  double litres = 0.0;

  std::uint64_t advance(const std::array<double, io::kMaxValves>& duties, double dt_s) {
    for (std::size_t i = 0; i < slope.size(); ++i) {
      const double s = duties[i];
      if (s <= 0) continue;
      const double q = s >= 100 ? held_open_flow(i) : slope[i] * s + intercept[i];
      litres += q / 60.0 * dt_s;
    }
    return static_cast<std::uint64_t>(litres * k);
  }
  double held_open_flow(std::size_t i) const {
    return (slope[i] * 100 + intercept[i]) * held_open_gain[i];
  }
};

// One tick of the daemon's 20 Hz: the run's duties for 50 ms, then its update.
double run_until_idle_one_tick(CalibrationRun& run, MadeUpBoom& boom, double t,
                               double* last_progress) {
  constexpr double kTick = 0.05;
  const std::uint64_t pulses = boom.advance(run.duties(), kTick);
  t += kTick;
  run.update(t, pulses);
  if (last_progress != nullptr) {
    EXPECT_GE(run.progress(), *last_progress) << "progress went back at t " << t;
    *last_progress = run.progress();
  }
  return t;
}

// Ticks the run at the daemon's 20 Hz until it stops commanding the valves (or `limit_s`).
double run_until_idle(CalibrationRun& run, MadeUpBoom& boom, double t, double limit_s,
                      double* last_progress = nullptr) {
  constexpr double kTick = 0.05;
  std::uint64_t pulses = static_cast<std::uint64_t>(boom.litres * boom.k);
  while (run.running() && t < limit_s) {
    pulses = boom.advance(run.duties(), kTick);
    t += kTick;
    run.update(t, pulses);
    if (last_progress != nullptr) {
      EXPECT_GE(run.progress(), *last_progress) << "progress went back at t " << t;
      *last_progress = run.progress();
    }
  }
  return t;
}

TEST(CalibrationRun, CatchTestOpensEveryValveThenTakesTheCollectedVolume) {
  CalibrationRun run(3);
  MadeUpBoom boom;
  ASSERT_EQ(run.start_catch_test(10.0, 0.0, 0), "");
  EXPECT_TRUE(run.running());
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(run.duties()[i], 100.0);
  EXPECT_EQ(run.duties()[3], 0.0) << "a valve beyond the boom was opened";
  EXPECT_NE(run.start_nozzle_sweep({}, 0.0, 0), "") << "a second calibration started";
  std::string error;
  EXPECT_FALSE(run.enter_volume(1.0, 8500.0, 25.0, error)) << "a volume taken mid-run";
  const double end = run_until_idle(run, boom, 0.0, 30.0);
  EXPECT_NEAR(end, 10.0 + CalibrationRun::kDrainS, 0.06);
  EXPECT_EQ(run.state(), CalibrationState::kAwaitingVolume);
  for (double d : run.duties()) EXPECT_EQ(d, 0.0);
  // A typo (ten times the volume, a tenth): the K would be 90 % or 900 % off: refused, and the
  // catch test still awaits its volume.
  for (double typo : {10.0, 0.1}) {
    EXPECT_FALSE(run.enter_volume(boom.litres * typo, 8500.0, 25.0, error)) << typo;
    EXPECT_NE(error.find("calibration.meter_max_change_pct"), std::string::npos) << error;
    EXPECT_EQ(run.state(), CalibrationState::kAwaitingVolume);
  }
  // What the user collected: the boom's true litres over the run.
  const auto result = run.enter_volume(boom.litres, 8500.0, 25.0, error);
  ASSERT_TRUE(result) << error;
  EXPECT_NEAR(result->pulses_per_litre, 8670.0, 8670.0 * 1e-3);
  EXPECT_NEAR(result->error_pct, (8500.0 - 8670.0) / 8670.0 * 100.0, 0.1);
  EXPECT_EQ(run.state(), CalibrationState::kDone);
  EXPECT_EQ(run.progress(), 1.0);
}

TEST(CalibrationRun, TheSweepRecoversEachNozzlesOwnLine) {
  CalibrationRun run(3);
  MadeUpBoom boom;
  NozzleSweepPlan plan;
  plan.duties_pct = {20, 40, 60, 80};
  plan.settle_s = 0.5;
  plan.measure_s = 3.0;
  plan.pressure_mpa = 0.3;
  plan.pulses_per_litre = boom.k;
  ASSERT_EQ(run.start_nozzle_sweep(plan, 0.0, 0), "");
  EXPECT_EQ(run.duties()[0], 20.0);
  EXPECT_EQ(run.duties()[1], 0.0) << "more than one nozzle open";
  double progress = 0;
  std::array<double, io::kMaxValves> held_open_seen{};
  bool two_open = false;
  double end = 0.0;
  for (double t = 0.0; run.running() && t < 200.0;) {
    end = t = run_until_idle_one_tick(run, boom, t, &progress);
    for (std::size_t i = 0; i < 3; ++i)
      if (run.duties()[i] == 100.0) held_open_seen[i] = 1;
    two_open = two_open || std::count_if(run.duties().begin(), run.duties().end(),
                                         [](double d) { return d > 0; }) > 1;
  }
  EXPECT_NEAR(end, 3 * 5 * 3.5 + CalibrationRun::kPumpLeadInS, 3 * 5 * 0.1)
      << "the sweep's length: 4 duties and the held-open point per nozzle";
  EXPECT_FALSE(two_open) << "more than one nozzle open at once";
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(held_open_seen[i], 1) << "nozzle " << i;
  EXPECT_EQ(run.state(), CalibrationState::kDone);
  EXPECT_EQ(progress, 1.0);
  for (double d : run.duties()) EXPECT_EQ(d, 0.0) << "a valve left open";
  const auto fits = run.take_fits();
  ASSERT_EQ(fits.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    ASSERT_TRUE(fits[i]) << "nozzle " << i;
    EXPECT_NEAR(fits[i]->line.slope_l_per_min_per_pct, boom.slope[i], boom.slope[i] * 0.03)
        << "nozzle " << i;
    EXPECT_NEAR(fits[i]->line.intercept_l_per_min, boom.intercept[i], 0.01) << "nozzle " << i;
    EXPECT_DOUBLE_EQ(fits[i]->line.calibration_pressure_mpa, 0.3);
    EXPECT_GT(fits[i]->r_squared, 0.999) << "the held-open point was fitted into the line";
    EXPECT_EQ(fits[i]->points_used, 4u);
    EXPECT_NEAR(fits[i]->line.full_open_flow_l_per_min, boom.held_open_flow(i),
                boom.held_open_flow(i) * 0.01)
        << "nozzle " << i;
  }
  EXPECT_NE(run.message().find("3 full-open flows"), std::string::npos) << run.message();
}

// full_open = false: the plan's duties only, the full-open flows unknown. A nozzle that passes
// less held open than its line at the highest duty (a valve that does not open fully, a meter
// that misses pulses) gets no full-open flow either.
TEST(CalibrationRun, TheHeldOpenPointIsOptionalAndAnImplausibleOneIsNotKept) {
  for (bool full_open : {false, true}) {
    CalibrationRun run(3);
    MadeUpBoom boom;
    boom.held_open_gain[1] = 0.7;  // held open: 0.7 x the line at 100 %, below it at 80 %
    NozzleSweepPlan plan;
    plan.duties_pct = {20, 80};
    plan.settle_s = 0.5;
    plan.measure_s = 3.0;
    plan.pulses_per_litre = boom.k;
    plan.full_open = full_open;
    ASSERT_EQ(run.start_nozzle_sweep(plan, 0.0, 0), "");
    const double end = run_until_idle(run, boom, 0.0, 200.0);
    EXPECT_NEAR(end, 3 * (full_open ? 3 : 2) * 3.5 + CalibrationRun::kPumpLeadInS, 1.0);
    const auto fits = run.take_fits();
    ASSERT_EQ(fits.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i) {
      ASSERT_TRUE(fits[i]);
      const bool kept = full_open && i != 1;
      EXPECT_EQ(fits[i]->line.full_open_flow_l_per_min > 0, kept)
          << "nozzle " << i << " full_open " << full_open;
    }
  }
}

TEST(CalibrationRun, CancelClosesTheValvesAndKeepsNoResult) {
  CalibrationRun run(3);
  MadeUpBoom boom;
  NozzleSweepPlan plan;
  plan.pulses_per_litre = boom.k;
  ASSERT_EQ(run.start_nozzle_sweep(plan, 0.0, 0), "");
  run_until_idle(run, boom, 0.0, 5.0);
  ASSERT_TRUE(run.running());
  run.cancel("Stop");
  EXPECT_FALSE(run.running());
  EXPECT_EQ(run.state(), CalibrationState::kCancelled);
  for (double d : run.duties()) EXPECT_EQ(d, 0.0);
  EXPECT_TRUE(run.take_fits().empty());
  EXPECT_EQ(run.start_catch_test(0.5, 5.0, 0), "the catch test must last 1..600 s");
}

fs::path temp_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("weedspray-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(CalibrationStore, SavedResultsComeBackAndTheRightOnesAreUsed) {
  const fs::path file = temp_dir("calibration") / "calibration.toml";
  EXPECT_FALSE(load_calibration(file).meter) << "a missing file gave a meter";
  StoredCalibration stored;
  stored.meter = control::calibrate_flow_meter(8670, 1.0, 8500.0);
  stored.nozzles.resize(3);
  control::NozzleLineFit good;
  good.line = {0.0056, 0.07, 0.3, 0.71};
  good.r_squared = 0.995;
  good.points_used = 4;
  control::NozzleLineFit poor = good;
  poor.line.slope_l_per_min_per_pct = 0.009;
  poor.r_squared = 0.90;
  stored.nozzles[0] = good;
  stored.nozzles[2] = poor;  // nozzle 1: never calibrated
  save_calibration(file, stored);
  EXPECT_FALSE(fs::exists(file.string() + ".tmp")) << "the temporary file was left";

  const StoredCalibration back = load_calibration(file);
  ASSERT_TRUE(back.meter);
  EXPECT_DOUBLE_EQ(back.meter->pulses_per_litre, 8670.0);
  EXPECT_DOUBLE_EQ(back.meter->configured_pulses_per_litre, 8500.0);
  EXPECT_DOUBLE_EQ(meter_pulses_per_litre(8500.0, back), 8670.0);
  EXPECT_DOUBLE_EQ(meter_pulses_per_litre(8500.0, StoredCalibration{}), 8500.0);

  const control::NozzleLine configured{0.00393, 0.217, 0.4, 0.0};
  std::array<NozzleLineChoice, 4> lines;
  choose_nozzle_lines(configured, back, 0.98, lines);
  EXPECT_EQ(lines[0].source, LineSource::kCalibration);
  EXPECT_DOUBLE_EQ(lines[0].line.slope_l_per_min_per_pct, 0.0056);
  EXPECT_DOUBLE_EQ(lines[0].line.intercept_l_per_min, 0.07);
  EXPECT_DOUBLE_EQ(lines[0].line.calibration_pressure_mpa, 0.3);
  EXPECT_DOUBLE_EQ(lines[0].line.full_open_flow_l_per_min, 0.71) << "its own, held open";
  EXPECT_EQ(lines[1].source, LineSource::kConfig);
  EXPECT_DOUBLE_EQ(lines[1].line.slope_l_per_min_per_pct, 0.00393);
  EXPECT_EQ(lines[2].source, LineSource::kPoorFit) << "an R^2 of 0.90 was used";
  EXPECT_DOUBLE_EQ(lines[2].line.slope_l_per_min_per_pct, 0.00393);
  EXPECT_EQ(lines[3].source, LineSource::kConfig);
  // The bar is the configured one: at 0.85 the poor fit is good enough.
  choose_nozzle_lines(configured, back, 0.85, lines);
  EXPECT_EQ(lines[2].source, LineSource::kCalibration);
  EXPECT_DOUBLE_EQ(lines[2].line.slope_l_per_min_per_pct, 0.009);
  EXPECT_DOUBLE_EQ(lines[2].line.full_open_flow_l_per_min, 0.71);
  // A calibrated line never takes the configured line's full-open flow.
  choose_nozzle_lines({0.00393, 0.217, 0.4, 0.9}, back, 0.98, lines);
  EXPECT_DOUBLE_EQ(lines[1].line.full_open_flow_l_per_min, 0.9) << "the configured line's own";
  StoredCalibration unmeasured = back;
  unmeasured.nozzles[0]->line.full_open_flow_l_per_min = 0.0;
  choose_nozzle_lines({0.00393, 0.217, 0.4, 0.9}, unmeasured, 0.98, lines);
  EXPECT_DOUBLE_EQ(lines[0].line.full_open_flow_l_per_min, 0.0) << "unknown stays unknown";
}

TEST(CalibrationStore, ACorruptFileIsNamedAndNothingIsUsed) {
  const fs::path file = temp_dir("calibration-corrupt") / "calibration.toml";
  std::ofstream(file) << "[meter\npulses_per_litre = 1\n";
  std::string error;
  const StoredCalibration back = load_calibration(file, &error);
  EXPECT_FALSE(back.meter);
  EXPECT_TRUE(back.nozzles.empty());
  EXPECT_NE(error.find("calibration.toml:"), std::string::npos) << error;
}

}  // namespace
}  // namespace weedspray::daemon
