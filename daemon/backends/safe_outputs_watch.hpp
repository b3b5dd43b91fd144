// SPDX-License-Identifier: Apache-2.0
// The exit watcher: weedspray-safe-outputs --when-closed FD --daemon-pid PID, started by
// weedsprayd (hardware mode) before it requests any line. FD is one end of a unix socket pair
// whose other end only the daemon holds. Once its outputs are open the daemon sends over it
// its fatal-exit writes with copies of their descriptors (emergency_write_handoff.hpp).
// Two signs of the daemon's end, whichever comes first:
// - PF_EXITING in /proc/PID/stat (supervision/process_exit_probe.hpp), polled every 10 ms:
//   set when the kernel starts to tear the daemon down (kill -9 included), long before it
//   closes the daemon's files; the watcher then writes every handed-over output safe through
//   its copies at once;
// - FD reading end-of-file (the kernel closed the daemon's end): the fallback.
// After end-of-file it closes its copies and requests every output at its safe value, retrying
// while the dying daemon's line requests are still being released (EBUSY). The unit's
// ExecStopPost stays as the second layer; it runs only after systemd saw the whole service end
// (seconds on a slow board).
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <vector>

#include "daemon/backends/backends.hpp"

namespace weedspray::daemon {

// Calls `write` (which appends its failures) until none of its failures is a busy line, or
// `retry_for` has passed since the first call; `failures` holds the last call's. Returns the
// number of calls.
int write_retrying_busy_lines(const std::function<void(std::vector<SafeWriteFailure>&)>& write,
                              std::vector<SafeWriteFailure>& failures,
                              std::chrono::nanoseconds retry_for,
                              std::chrono::nanoseconds retry_every);

// Loads the configuration first, from the daemon's output manifest when there is one (so
// nothing is left to read after the daemon is gone), ignores
// SIGTERM/SIGINT/SIGHUP (a stop signals the whole service: the watcher must outlive the
// daemon), waits, writes. Returns the exit status.
// daemon_pid <= 0: only end-of-file is watched.
int watch_and_write_safe_outputs(int fd, int daemon_pid, const std::filesystem::path& config_path,
                                 const std::filesystem::path& manifest_path, const char* program);

}  // namespace weedspray::daemon
