// SPDX-License-Identifier: Apache-2.0
// The configuration a run starts with: a simulation needs no file and keeps its records apart
// from the sprayer's; the board reads its file and names each safeguard it is allowed to lack.
#include "daemon/config/run_config.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>

namespace weedspray::daemon {
namespace {

class RunConfigTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        std::filesystem::temp_directory_path() / ("run_config_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    ::setenv("XDG_STATE_HOME", (dir_ / "state").c_str(), 1);
  }
  void TearDown() override {
    ::unsetenv("XDG_STATE_HOME");
    std::filesystem::remove_all(dir_);
  }

  std::filesystem::path dir_;
};

TEST_F(RunConfigTest, SimulationWithoutFileUsesDefaultsAndItsOwnStateFolder) {
  Options options;
  options.sim = true;
  options.config_path = (dir_ / "missing.toml").string();
  const RunConfig run = load_run_config(options);
  EXPECT_EQ(run.config.daemon.state_dir, (dir_ / "state" / "weedspray-sim").string());
  EXPECT_TRUE(run.config.log.dir.empty());
  EXPECT_TRUE(run.warnings.empty());
  EXPECT_NE(run.note.find("simulating on the built-in defaults"), std::string::npos) << run.note;
  EXPECT_NE(run.note.find("missing.toml"), std::string::npos) << run.note;
}

TEST_F(RunConfigTest, StateDirOptionOverridesBothModes) {
  Options options;
  options.sim = true;
  options.config_path = (dir_ / "missing.toml").string();
  options.state_dir = (dir_ / "chosen").string();
  EXPECT_EQ(load_config_with_overrides(options).daemon.state_dir, options.state_dir);
}

TEST_F(RunConfigTest, BoardNeedsItsFileAndWarnsOfEachOptOut) {
  Options options;
  options.config_path = (dir_ / "missing.toml").string();
  EXPECT_THROW(load_run_config(options), ConfigError);

  const std::filesystem::path file = dir_ / "weedspray.toml";
  std::ofstream(file) << "[gpio]\nheartbeat_opt_out = true\nestop_opt_out = true\n";
  options.config_path = file.string();
  options.config_given = true;
  const RunConfig run = load_run_config(options);
  ASSERT_EQ(run.warnings.size(), 2U);
  EXPECT_EQ(run.warnings[0], kNoHeartbeatWarning);
  EXPECT_EQ(run.warnings[1], kNoEstopWarning);
  EXPECT_TRUE(run.note.empty());
  EXPECT_EQ(run.config.daemon.state_dir.find("weedspray-sim"), std::string::npos)
      << "the board's records went to the simulation's folder";
}

}  // namespace
}  // namespace weedspray::daemon
