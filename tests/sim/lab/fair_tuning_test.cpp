// SPDX-License-Identifier: Apache-2.0
// The fair tuning: one search for both controllers, the fuzzy corrections earning
// their place, and the daemon's default controller being the one that wins on machines the
// search never saw.
#include "lab/experiments/fair_tuning.hpp"

#include <gtest/gtest.h>

#include <string>
#include <variant>

#include "daemon/config/config_schema.hpp"
#include "lab/experiments/vocabulary.hpp"

namespace weedspray::lab::experiments {
namespace {

const daemon::DefaultValue& schema_default(std::string_view section, std::string_view name) {
  for (const auto& key : daemon::config_keys())
    if (key.section == section && key.name == name) return key.default_value;
  throw std::runtime_error("no such key");
}

double schema_double(std::string_view name) {
  return std::get<double>(schema_default("pressure", name));
}

TEST(FairTuning, BothControllersGetTheSameBudgetFromTheSameStart) {
  TuningSet set = training_set(1, 1);
  set.points = {{0.3, 2}};
  const FairTuningResult r = tune_fair(set, 24);
  EXPECT_EQ(r.pid.evaluations, 24);
  EXPECT_EQ(r.fuzzy_pid.evaluations, 24);
  // The search moved from the centre of the box and improved on it.
  const FuzzyPidConfig centre = [] {
    FuzzyPidConfig c = fair_tuned_pid_config();
    c.base.gains = {31.6227766, 100.0, 0.0316227766};
    return c;
  }();
  EXPECT_LT(r.pid.training_itae, mean_itae(PressureControlMode::kPid, centre, set));
}

TEST(FairTuning, RecordedGainsAreInsideTheSearchBounds) {
  for (const FuzzyPidConfig& c : {fair_tuned_pid_config(), fair_tuned_fuzzy_pid_config()}) {
    EXPECT_GT(c.base.gains.kp, 1.0 * 1.05);
    EXPECT_LT(c.base.gains.kp, 1000.0 / 1.05);
    EXPECT_GT(c.base.gains.ki, 1.0 * 1.05);
    EXPECT_LT(c.base.gains.ki, 10000.0 / 1.05);
    EXPECT_GT(c.base.gains.kd, 1e-4 * 1.05);
    EXPECT_LT(c.base.gains.kd, 10.0 / 1.05);
  }
}

// Zeroing the fuzzy correction weights leaves a PID with the fuzzy's base gains: it must do
// worse on the training set, or the fuzzy part does nothing.
TEST(FairTuning, FuzzyCorrectionsLowerTheTrainingItae) {
  const TuningSet set = training_set(1);
  const FuzzyPidConfig fuzzy = fair_tuned_fuzzy_pid_config();
  FuzzyPidConfig zeroed = fuzzy;
  zeroed.correction_weights = {};
  EXPECT_LT(mean_itae(PressureControlMode::kFuzzyPid, fuzzy, set),
            mean_itae(PressureControlMode::kFuzzyPid, zeroed, set));
}

TEST(FairTuning, DaemonDefaultIsTheControllerThatWinsOnHeldOutMachines) {
  const StepFleetResult r =
      run_step_fleet({1, 4, false}, fair_tuned_pid_config(), fair_tuned_fuzzy_pid_config());
  const bool fuzzy_wins = r.fuzzy_pid.operating_points_itae.mean < r.pid.operating_points_itae.mean;
  EXPECT_EQ(std::get<std::string>(schema_default("pressure", "controller")),
            fuzzy_wins ? "fuzzy_pid" : "pid");
  const FuzzyPidConfig winner =
      fuzzy_wins ? fair_tuned_fuzzy_pid_config() : fair_tuned_pid_config();
  EXPECT_DOUBLE_EQ(schema_double("kp"), winner.base.gains.kp);
  EXPECT_DOUBLE_EQ(schema_double("ki"), winner.base.gains.ki);
  EXPECT_DOUBLE_EQ(schema_double("kd"), winner.base.gains.kd);
  EXPECT_DOUBLE_EQ(schema_double("cp"), winner.correction_weights.kp);
  EXPECT_DOUBLE_EQ(schema_double("ci"), winner.correction_weights.ki);
  EXPECT_DOUBLE_EQ(schema_double("cd"), winner.correction_weights.kd);
  EXPECT_DOUBLE_EQ(schema_double("range_mpa"), winner.error_range);
}

}  // namespace
}  // namespace weedspray::lab::experiments
