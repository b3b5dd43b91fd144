// SPDX-License-Identifier: Apache-2.0
// ReloadConfig and SIGHUP (main thread): the files are read and parsed and the model probed on
// a thread of its own (seconds for a large model on a slow board), while the main loop goes on
// feeding the watchdog, judging alarms and serving the bus; each tick applies a finished job.
// Callers that arrive meanwhile wait for the next job, which reads the files as they are then.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "daemon/bus/status.hpp"
#include "daemon/config/config.hpp"
#include "daemon/config/options.hpp"
#include "daemon/supervision/alarms.hpp"
#include "daemon/supervision/operation.hpp"

namespace weedspray::daemon {

class ConfigReloads {
 public:
  // `running`: the configuration in use, replaced by what may change live in a reload.
  ConfigReloads(const Options& options, Config& running, Operation& operation,
                AlarmEvaluator& alarms)
      : options_(options), running_(running), operation_(operation), alarms_(alarms) {}

  // `reply` (may be empty) gets the outcome once the job that reads the files is applied.
  void request(ReloadReply reply);
  // Each tick: a finished job applied, its callers answered, the next job started.
  void finish();

 private:
  struct Job {
    std::vector<ReloadReply> waiters;
    std::optional<Config> config;
    std::string error;
    std::atomic<bool> done{false};
    std::jthread thread;  // last: joined before the rest goes
  };

  void start();
  CommandResult apply(const Config& fresh);

  const Options& options_;
  Config& running_;
  Operation& operation_;
  AlarmEvaluator& alarms_;
  std::vector<ReloadReply> waiters_;  // asked for a reload not yet started
  std::unique_ptr<Job> job_;
};

}  // namespace weedspray::daemon
