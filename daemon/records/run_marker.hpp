// SPDX-License-Identifier: Apache-2.0
// Whether the last run ended in an orderly stop: a marker file in the state folder, written at
// start and removed by an orderly exit. Left behind by a crash, kill -9, the watchdog or a power
// cut, it keeps the next start from spraying by itself (daemon.autostart).
#pragma once

#include <filesystem>

namespace weedspray::daemon {

class RunMarker {
 public:
  // Notes whether `file` was left by a run that did not end in order, then writes it for this
  // run. Throws std::runtime_error naming the file when it cannot be written.
  explicit RunMarker(std::filesystem::path file);

  bool previous_run_unfinished() const { return previous_run_unfinished_; }
  // This run ends in order: the marker goes (an error is ignored: the next start then only
  // waits for Start).
  void finish() noexcept;

 private:
  std::filesystem::path file_;
  bool previous_run_unfinished_ = false;
};

}  // namespace weedspray::daemon
