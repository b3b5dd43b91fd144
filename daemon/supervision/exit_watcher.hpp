// Starts the exit watcher (weedspray-safe-outputs --when-closed, see
// backends/safe_outputs_watch.hpp) beside this program: a separate process that writes every
// output safe within milliseconds of this one ending, however it ends.
#pragma once

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

}  // namespace weedspray::daemon
