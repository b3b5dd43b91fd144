// The exit watcher: weedspray-safe-outputs --when-closed FD, started by weedsprayd (hardware
// mode) before it requests any line. It waits until FD, the read end of a pipe whose only write
// end the daemon holds, reads end-of-file: the kernel closes that end when the daemon's process
// ends, however it ends (kill -9 and crashes its handlers could not run in included). It then
// writes every output safe within milliseconds, retrying while the dying daemon's line requests
// are still being released (EBUSY). The unit's ExecStopPost stays as the second layer; it runs
// only after systemd saw the whole service end (seconds on a slow board).
#pragma once

#include <filesystem>

namespace weedspray::daemon {

// Loads the configuration first (so nothing is left to read after the daemon is gone), ignores
// SIGTERM/SIGINT/SIGHUP (a stop signals the whole service: the watcher must outlive the
// daemon), waits, writes. Returns the exit status.
int watch_and_write_safe_outputs(int fd, const std::filesystem::path& config_path,
                                 const char* program);

}  // namespace weedspray::daemon
