// SPDX-License-Identifier: Apache-2.0
// The daemon keeps an exit watcher running: one that ended is reaped and started again, at most
// once per retry interval; one that cannot be started is reported lost (the exit_watcher_lost
// alarm). Real child processes stand in for weedspray-safe-outputs.
#include "daemon/supervision/exit_watcher.hpp"

#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;
using State = ExitWatcherKeeper::State;

// Calls check(now) until it says something else than kRunning (the child ends by itself).
ExitWatcherKeeper::Check next_change(ExitWatcherKeeper& keeper, std::chrono::nanoseconds now) {
  for (int i = 0; i < 500; ++i) {
    const ExitWatcherKeeper::Check check = keeper.check(now);
    if (check.state != State::kRunning) return check;
    std::this_thread::sleep_for(10ms);
  }
  return {};
}

ExitWatcherKeeper keeper_of(const std::filesystem::path& program) {
  ExitWatcherKeeper::Launch launch{"/nonexistent/weedspray.toml", "", program};
  std::string error;
  const ExitWatcher first = start_exit_watcher(launch.config, launch.manifest, program, error);
  return ExitWatcherKeeper(launch, first, error, 1s);
}

TEST(ExitWatcherKeeper, AWatcherThatEndsIsStartedAgainAtMostOnceARetryInterval) {
  // /bin/true ends at once, like a watcher that crashed.
  ExitWatcherKeeper keeper = keeper_of("/bin/true");
  const int first = keeper.watcher().pid;
  ASSERT_GT(first, 0);
  const ExitWatcherKeeper::Check restarted = next_change(keeper, 0s);
  EXPECT_EQ(restarted.state, State::kRestarted);
  EXPECT_NE(restarted.what.find("exited with status 0"), std::string::npos) << restarted.what;
  EXPECT_GT(keeper.watcher().pid, 0);
  EXPECT_NE(keeper.watcher().pid, first);
  // It ended again within the interval: lost until the interval has passed.
  const ExitWatcherKeeper::Check lost = next_change(keeper, 500ms);
  EXPECT_EQ(lost.state, State::kLost);
  EXPECT_EQ(keeper.watcher().pid, -1);
  EXPECT_EQ(keeper.check(900ms).state, State::kLost);
  // Started again after the interval, but one that keeps ending at once is still no watcher.
  const ExitWatcherKeeper::Check again = keeper.check(1100ms);
  EXPECT_TRUE(again.started);
  EXPECT_EQ(again.state, State::kLost);
}

TEST(ExitWatcherKeeper, ALivingWatcherIsLeftAloneAndAKilledOneReplaced) {
  const auto script = std::filesystem::temp_directory_path() / "weedspray_watcher_stand_in.sh";
  std::ofstream(script) << "#!/bin/sh\nexec sleep 30\n";
  std::filesystem::permissions(script, std::filesystem::perms::owner_all);
  ExitWatcherKeeper keeper = keeper_of(script);
  const int first = keeper.watcher().pid;
  ASSERT_GT(first, 0);
  EXPECT_EQ(keeper.check(0s).state, State::kRunning);
  EXPECT_EQ(keeper.watcher().pid, first);
  ::kill(first, SIGKILL);
  const ExitWatcherKeeper::Check restarted = next_change(keeper, 0s);
  EXPECT_EQ(restarted.state, State::kRestarted);
  EXPECT_TRUE(restarted.started);
  EXPECT_NE(restarted.what.find("killed by signal 9"), std::string::npos) << restarted.what;
  EXPECT_EQ(keeper.check(2s).state, State::kRunning) << "the new one lives";
  // The stand-in still running ends with the test (never kill(-1): that signals everything).
  const int last = keeper.watcher().pid;
  if (last > 0) {
    ::kill(last, SIGKILL);
    next_change(keeper, 5s);
  }
  if (keeper.watcher().pid > 0) ::kill(keeper.watcher().pid, SIGKILL);
  std::filesystem::remove(script);
}

TEST(ExitWatcherKeeper, AWatcherThatCannotStartIsLostSayingWhy) {
  ExitWatcherKeeper keeper = keeper_of("/nonexistent/weedspray-safe-outputs");
  EXPECT_EQ(keeper.watcher().pid, -1);
  const ExitWatcherKeeper::Check lost = keeper.check(0s);
  EXPECT_EQ(lost.state, State::kLost);
  EXPECT_NE(lost.what.find("/nonexistent/weedspray-safe-outputs"), std::string::npos) << lost.what;
}

TEST(ExitWatcherKeeper, KeepsNothingWhenToldNothing) {
  ExitWatcherKeeper keeper;
  EXPECT_EQ(keeper.check(0s).state, State::kRunning);
}

}  // namespace
}  // namespace weedspray::daemon
