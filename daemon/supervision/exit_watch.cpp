// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/exit_watch.hpp"

#include <spdlog/spdlog.h>

#include <cstring>

#include "daemon/backends/emergency_write_handoff.hpp"
#include "daemon/backends/output_manifest.hpp"

namespace weedspray::daemon {

std::optional<ExitWatch> ExitWatch::arm(const Config& config, const Options& options) {
  if (!options.sim && !options.output_manifest.empty()) {
    try {
      write_output_manifest(config, options.output_manifest);
    } catch (const std::exception& error) {
      spdlog::critical("{}: the safe writers would depend on the editable files; not starting",
                       error.what());
      return std::nullopt;
    }
  }
  ExitWatcherKeeper keeper;  // keeps nothing in the self-test build: no watcher, no handoff
#ifndef WEEDSPRAY_SELFTEST_NO_FAILSAFE
  // Hardware mode: before any line is requested, a watcher process that writes the outputs
  // safe when this one ends in any way (kill -9 included); ExecStopPost is the second layer.
  if (!options.sim) {
    const ExitWatcherKeeper::Launch launch{options.config_path, options.output_manifest,
                                           default_exit_watcher_program()};
    std::string error;
    const ExitWatcher watcher =
        start_exit_watcher(launch.config, launch.manifest, launch.program, error);
    if (watcher.pid < 0)
      spdlog::error(
          "exit watcher not started ({}): after a kill -9 only ExecStopPost closes "
          "the valves",
          error);
    else
      spdlog::info("exit watcher started (pid {})", watcher.pid);
    keeper = ExitWatcherKeeper(launch, watcher,
                               error.empty() ? "" : "exit watcher not started: " + error);
  }
#endif
  return ExitWatch(std::move(keeper));
}

void ExitWatch::hand_outputs() {
  const int handed = hand_emergency_writes(keeper_.watcher().socket_fd);
  if (handed < 0)
    spdlog::warn(
        "exit watcher: outputs not handed over ({}): it writes them only after this process "
        "is gone",
        std::strerror(-handed));
  else
    spdlog::info("exit watcher (pid {}) holds the safe writes of {} outputs", keeper_.watcher().pid,
                 handed);
}

bool ExitWatch::running(std::chrono::nanoseconds now) {
  const ExitWatcherKeeper::Check check = keeper_.check(now);
  if (check.started) {
    spdlog::warn("{}: started again (pid {})", check.what, keeper_.watcher().pid);
    hand_outputs();
  }
  if (check.state != ExitWatcherKeeper::State::kLost) {
    lost_said_.clear();
    return true;
  }
  if (check.what != lost_said_) spdlog::error("{}", check.what);
  lost_said_ = check.what;
  return false;
}

}  // namespace weedspray::daemon
