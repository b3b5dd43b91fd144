// SPDX-License-Identifier: Apache-2.0
// The run's totals are saved by the as-applied writer thread, on its own, while the machine
// sprays: the main loop never calls persist() (its fsync stays off the main loop).
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>

#include "daemon/records/run_records.hpp"
#include "daemon/records/totals.hpp"
#include "tests/sim/daemon/run_until.hpp"
#include "tests/sim/daemon/spraying_machine.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

TEST(RunRecords, TheWriterSavesTheTotalsWhileSprayingWithoutTheMainLoop) {
  const fs::path state =
      fs::temp_directory_path() / ("weedspray-records-save-" + std::to_string(::getpid()));
  fs::remove_all(state);
  fs::create_directories(state);
  SprayingMachine m(1.0);
  m.config.daemon.state_dir = state.string();
  RunRecords records(m.config, /*from_zero=*/true);
  records.open_log(m.config);  // the first save: nothing sprayed yet
  const fs::path file = state / "totals.toml";
  ASSERT_EQ(load_totals(file).volume_l, 0.0);
  m.start();
  records.start_writer(*m.sprayer, 0, 200ms);
  // The machine sprays; the test thread only drives the simulated world, as the daemon's main
  // loop would, and never asks for a save.
  EXPECT_TRUE(run_until(
      m.backends, [&] { return load_totals(file).volume_l > 0.001; }, 10s))
      << "the totals on disk never grew while spraying: " << load_totals(file).volume_l << " L";
  const Totals saved = load_totals(file);
  EXPECT_TRUE(saved.log.known) << "the save carries no as-applied mark";
  EXPECT_LE(saved.volume_l, records.totals().volume_l + 1e-9);
  m.sprayer->stop();
  records.stop_writer();
  fs::remove_all(state);
}

}  // namespace
}  // namespace weedspray::daemon
