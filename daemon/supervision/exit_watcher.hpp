// SPDX-License-Identifier: Apache-2.0
// Starts the exit watcher (weedspray-safe-outputs --when-closed, see
// backends/safe_outputs_watch.hpp) beside this program: a separate process that writes every
// output safe within milliseconds of this one ending, however it ends.
#pragma once

#include <chrono>
#include <filesystem>
#include <string>

namespace weedspray::daemon {

struct ExitWatcher {
  int pid = -1;
  // Held open (close-on-exec) until the process ends; carries only the handed-over outputs.
  int socket_fd = -1;
};

// `program` is the watcher's executable (default: weedspray-safe-outputs in this program's
// folder); it reads `manifest_path` (the daemon's output manifest; empty: none) before
// `config_path`. Returns pid -1 with `error` set when it cannot be started.
ExitWatcher start_exit_watcher(const std::filesystem::path& config_path,
                               const std::filesystem::path& manifest_path,
                               const std::filesystem::path& program, std::string& error);

// weedspray-safe-outputs in the folder of /proc/self/exe.
std::filesystem::path default_exit_watcher_program();

// Keeps an exit watcher running beside the daemon (hardware mode): check() reaps one that ended
// (it is this process's child), closes its socket and starts another, at most once per
// `retry_every`. The caller hands each newly started watcher the outputs' safe writes. A
// watcher that ends within `retry_every` of its start counts as lost until one lives that long.
class ExitWatcherKeeper {
 public:
  struct Launch {
    std::filesystem::path config;
    std::filesystem::path manifest;
    std::filesystem::path program;
  };
  enum class State { kRunning, kRestarted, kLost };
  struct Check {
    State state = State::kRunning;
    std::string what;      // kRestarted, kLost: how the last one ended, or why none started
    bool started = false;  // a new watcher was started: hand it the outputs
  };

  ExitWatcherKeeper() = default;  // keeps nothing (simulation, self-test build)
  ExitWatcherKeeper(Launch launch, ExitWatcher started, std::string start_error,
                    std::chrono::nanoseconds retry_every = std::chrono::seconds(1));

  Check check(std::chrono::nanoseconds now);
  [[nodiscard]] const ExitWatcher& watcher() const noexcept { return watcher_; }

 private:
  bool keeping_ = false;
  Launch launch_;
  ExitWatcher watcher_;
  std::string last_error_;
  std::chrono::nanoseconds retry_every_{};
  std::chrono::nanoseconds last_start_{};
  bool started_once_ = false;
  bool ending_at_once_ = false;  // the last one ended within retry_every_ of its start
};

}  // namespace weedspray::daemon
