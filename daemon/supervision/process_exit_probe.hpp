// SPDX-License-Identifier: Apache-2.0
// Sees a process begin to die before the kernel has torn it down. The kernel's do_exit() sets
// PF_EXITING in the task's flags (field 9 of /proc/PID/stat) first thing, before it frees the
// process's memory (exit_mm: slow for a large mlock'd daemon, hundreds of ms on a slow or
// emulated CPU) and only then closes its files - which is when a pipe or socket to the process
// reads end-of-file. A stopped (SIGSTOP), stalled or busy process is not exiting: a hung daemon
// is the systemd watchdog's business, not this probe's.
#pragma once

#include <sys/types.h>

#include <cstddef>

namespace weedspray::daemon {

class ProcessExitProbe {
 public:
  ProcessExitProbe() = default;
  // Opens /proc/PID/stat and keeps it open: the open file stays bound to that process, so a
  // reused PID is never mistaken for it. valid() is false when it could not be opened.
  explicit ProcessExitProbe(pid_t pid);
  ~ProcessExitProbe();
  ProcessExitProbe(const ProcessExitProbe&) = delete;
  ProcessExitProbe& operator=(const ProcessExitProbe&) = delete;
  ProcessExitProbe(ProcessExitProbe&& other) noexcept;
  ProcessExitProbe& operator=(ProcessExitProbe&& other) noexcept;

  bool valid() const noexcept { return fd_ >= 0; }
  // True once the process has begun to exit: PF_EXITING set, a zombie, or already reaped.
  // One pread of a small proc file; no allocation.
  bool exiting() const noexcept;

 private:
  int fd_ = -1;
};

// Field 9 ("flags") of a /proc/PID/stat line has PF_EXITING set, or its state is a zombie
// ('Z') or dead ('X'). False for text it cannot parse.
bool stat_line_says_exiting(const char* text, std::size_t length) noexcept;

}  // namespace weedspray::daemon
