// SPDX-License-Identifier: Apache-2.0
// The outputs watched from the main thread: the failed writes of every thread (the
// output_write_failed alarm), the safe writes retried while in Fault, the alarm lamp and
// buzzer, and at exit whether every output took its safe value.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "daemon/backends/backends.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "daemon/supervision/output_write_watch.hpp"

namespace weedspray::daemon {

class OutputChecks {
 public:
  // Once the loops run: what each output drives, and the safe writes that failed at start.
  void start(const Backends& backends, const SafeWriteErrors& unsafe);

  // Each tick: the outputs' failed writes since the last tick, and the safe writes still
  // failing (retried here while `in_fault`, when every output is meant to be safe): "" when
  // all is well, else a message naming each output.
  std::string check(const Sprayer& sprayer, Backends& backends, bool in_fault,
                    int write_failures_tolerated);
  // The LED lit while any alarm is latched, the buzzer while a fault is.
  void show_alarms(Backends& backends, bool any, bool fault);

  // At exit: every output safe, or each one that is not named. False when one is not.
  static bool report_safe_writes(const Backends& backends, const SafeWriteErrors& errors) noexcept;

 private:
  std::optional<OutputWriteWatch> watch_;
  SafeWriteErrors unsafe_{};  // -errno of safe writes that failed and still do
  std::array<std::uint64_t, kOutputRoleCount> main_thread_write_failures_{};
  std::array<std::uint64_t, kOutputRoleCount> failed_writes_seen_{};
  std::array<std::uint64_t, kOutputRoleCount> tolerated_seen_{};
  std::array<bool, kOutputRoleCount> rewrite_safe_{};  // refused a write: write it safe in Fault
};

}  // namespace weedspray::daemon
