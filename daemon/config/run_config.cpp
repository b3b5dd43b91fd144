// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/run_config.hpp"

#include <cstdlib>
#include <filesystem>

namespace weedspray::daemon {
namespace {

// Where a simulation keeps its totals and as-applied logs: never the sprayer's own records.
std::string sim_state_dir() {
  if (const char* xdg = std::getenv("XDG_STATE_HOME"); xdg != nullptr && *xdg == '/')
    return std::string(xdg) + "/weedspray-sim";
  if (const char* home = std::getenv("HOME"); home != nullptr && *home == '/')
    return std::string(home) + "/.local/state/weedspray-sim";
  return "/tmp/weedspray-sim";
}

bool defaults_only(const Options& options) {
  return options.sim && !options.config_given && !std::filesystem::exists(options.config_path);
}

}  // namespace

Config load_config_with_overrides(const Options& options) {
  Config config = defaults_only(options) ? default_config() : load_config(options.config_path);
  if (options.sim) {
    config.daemon.state_dir = sim_state_dir();
    config.log.dir.clear();
  }
  if (!options.state_dir.empty()) config.daemon.state_dir = options.state_dir;
  return config;
}

RunConfig load_run_config(const Options& options) {
  RunConfig run{load_config_with_overrides(options), {}, {}};
  if (!options.sim) {
    const bool no_heartbeat = require_heartbeat(run.config);
    const bool no_estop = require_estop(run.config);
    if (no_heartbeat) run.warnings.emplace_back(kNoHeartbeatWarning);
    if (no_estop) run.warnings.emplace_back(kNoEstopWarning);
  }
  if (defaults_only(options)) {
    run.note = "simulating on the built-in defaults (";
    run.note += options.config_path;
    run.note += " not found; --config FILE to use one)";
  }
  return run;
}

}  // namespace weedspray::daemon
