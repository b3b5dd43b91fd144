// SPDX-License-Identifier: Apache-2.0
// The safe writers outside this process (hardware mode): armed before any output line is
// requested (the output manifest they read, and the exit watcher), then kept running each tick
// (supervision/exit_watcher.hpp). A simulation has neither.
#pragma once

#include <chrono>
#include <optional>
#include <string>

#include "daemon/config/config.hpp"
#include "daemon/config/options.hpp"
#include "daemon/supervision/exit_watcher.hpp"

namespace weedspray::daemon {

class ExitWatch {
 public:
  // Writes options.output_manifest and starts the exit watcher (a failed start is logged: the
  // alarm follows). nullopt when the manifest cannot be written: the daemon must not start.
  static std::optional<ExitWatch> arm(const Config& config, const Options& options);

  // A watcher runs that the outputs' safe writes can be handed to.
  bool has_watcher() const noexcept { return keeper_.watcher().socket_fd >= 0; }
  // Hands the watcher the outputs' safe writes (once the backends registered them).
  void hand_outputs();
  // Each tick: a watcher that ended is started again and handed the outputs; false while none
  // runs (the exit_watcher_lost alarm, lost_because() says why).
  bool running(std::chrono::nanoseconds now);
  const std::string& lost_because() const noexcept { return lost_said_; }

 private:
  explicit ExitWatch(ExitWatcherKeeper keeper) : keeper_(std::move(keeper)) {}

  ExitWatcherKeeper keeper_;
  std::string lost_said_;  // logged once per cause
};

}  // namespace weedspray::daemon
