// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/output_checks.hpp"

#include <spdlog/spdlog.h>

#include <cstring>

namespace weedspray::daemon {

void OutputChecks::start(const Backends& backends, const SafeWriteErrors& unsafe) {
  watch_.emplace(backends.output_devices());
  unsafe_ = unsafe;
}

std::string OutputChecks::check(const Sprayer& sprayer, Backends& backends, bool in_fault,
                                int write_failures_tolerated) {
  OutputWriteCounters counters = sprayer.output_write_counters();
  for (std::size_t i = 0; i < kOutputRoleCount; ++i) {
    counters.failed_writes[i] += main_thread_write_failures_[i];
    // An output that refused a write may be left in any state (a valve stuck open): it is
    // written safe again from here once in Fault, and until that succeeds.
    if (counters.failed_writes[i] != failed_writes_seen_[i]) rewrite_safe_[i] = true;
    failed_writes_seen_[i] = counters.failed_writes[i];
  }
  if (in_fault) {
    for (std::size_t i = 0; i < kOutputRoleCount; ++i) {
      if (!rewrite_safe_[i] && unsafe_[i] == 0) continue;
      const bool was_unsafe = unsafe_[i] != 0;
      unsafe_[i] = backends.force_safe(static_cast<OutputRole>(i));
      if (unsafe_[i] != 0) continue;
      rewrite_safe_[i] = false;
      if (was_unsafe)
        spdlog::info("{} written safe again", output_role_name(static_cast<OutputRole>(i)));
    }
  }
  for (std::size_t i = 0; i < kOutputRoleCount; ++i) {
    counters.unsafe_error[i] = -unsafe_[i];
    // Tolerated failures are no fault, but a rising count says the bus is getting worse.
    const std::uint64_t tolerated = counters.tolerated_failures[i] - tolerated_seen_[i];
    if (tolerated > 0)
      spdlog::warn(
          "{}: {} failed write(s) superseded by the next ({} total; [dac] "
          "write_failures_tolerated = {} in a row)",
          output_role_name(static_cast<OutputRole>(i)), tolerated, counters.tolerated_failures[i],
          write_failures_tolerated);
    tolerated_seen_[i] = counters.tolerated_failures[i];
  }
  return watch_->update(counters);
}

void OutputChecks::show_alarms(Backends& backends, bool any, bool fault) {
  const auto count_failure = [this](OutputRole role, int result) {
    if (result != 0) ++main_thread_write_failures_[static_cast<std::size_t>(role)];
  };
  if (backends.led != nullptr) count_failure(OutputRole::kLed, backends.led->write(any ? 1 : 0));
  if (backends.buzzer != nullptr)
    count_failure(OutputRole::kBuzzer, backends.buzzer->write(fault ? 1 : 0));
}

// The exit status says so too, so systemd's ExecStopPost and the journal both see it.
bool OutputChecks::report_safe_writes(const Backends& backends,
                                      const SafeWriteErrors& errors) noexcept {
  try {
    const auto devices = backends.output_devices();
    bool all_safe = true;
    for (std::size_t i = 0; i < kOutputRoleCount; ++i) {
      if (errors[i] == 0) continue;
      all_safe = false;
      spdlog::critical("output NOT safe: {} ({}): safe value not written: {}",
                       output_role_name(static_cast<OutputRole>(i)), devices[i],
                       std::strerror(-errors[i]));
    }
    if (all_safe) spdlog::info("outputs safe: valves closed, pump off, return valve open");
    return all_safe;
  } catch (...) {
    return false;
  }
}

}  // namespace weedspray::daemon
