// SPDX-License-Identifier: Apache-2.0
// weedspray-safe-outputs: writes every configured output's safe value and exits; the unit's
// ExecStopPost after every exit of weedsprayd, kill -9 included (daemon/CMakeLists.txt says why
// it is not weedsprayd --safe-outputs, which does the same). With --when-closed it is the exit
// watcher weedsprayd starts beside itself (backends/safe_outputs_watch.hpp).
#include <CLI/CLI.hpp>
#include <string>

#include "daemon/backends/backends.hpp"
#include "daemon/backends/safe_outputs_watch.hpp"
#include "daemon/config/config.hpp"

int main(int argc, char** argv) {
  std::string config_path = weedspray::daemon::kDefaultConfigPath;
  std::string manifest_path;
  int watch_fd = -1;
  int daemon_pid = 0;
  CLI::App app{
      "weedspray-safe-outputs: write every output of the configuration at its safe value "
      "(valves and pump off, buzzer/LED/heartbeat low, return valve at dac.safe_value)"};
  app.add_option("--config", config_path, "main configuration file (drop-ins: conf.d/)");
  app.add_option("--manifest", manifest_path,
                 "weedsprayd's output manifest (its --output-manifest): used instead of --config "
                 "when it exists, so an edit after the daemon's start cannot break this writer");
  app.add_option("--when-closed", watch_fd,
                 "first wait until this unix socket (SOCK_SEQPACKET) reads end-of-file (weedsprayd "
                 "holds the other end: its process has ended)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--daemon-pid", daemon_pid,
                 "with --when-closed: weedsprayd's PID (this program's parent); its outputs are "
                 "written safe as soon as it starts to exit, through the descriptors it handed "
                 "over on the socket")
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  if (watch_fd >= 0)
    return weedspray::daemon::watch_and_write_safe_outputs(watch_fd, daemon_pid, config_path,
                                                           manifest_path, "weedspray-safe-outputs");
  return weedspray::daemon::write_safe_outputs(config_path, manifest_path,
                                               "weedspray-safe-outputs");
}
