// SPDX-License-Identifier: Apache-2.0
// What a reload (SIGHUP, ReloadConfig) changes in a running daemon. The live keys ([spray],
// [alarms], pressure.setpoint_mpa, the [daemon] levels) take effect at once, except the
// safety limits among them (config_schema.hpp, is_safety_limit): those keep their running
// value until a restart, so a typo in a reload cannot loosen a trip while spraying.
#pragma once

#include <string>
#include <vector>

#include "daemon/config/config.hpp"

namespace weedspray::daemon {

struct LiveReload {
  Config config;                         // the running configuration with the live keys applied
  std::vector<std::string> kept_limits;  // safety limits changed in the files, kept as running
  bool restart_needed = false;           // other keys changed too: they wait for a restart
};

// `running` updated from `fresh` (a configuration just loaded and validated). Throws
// ConfigError, naming where the set-point was set, when the new set-point is not below the
// running over-pressure trip (a raised trip would only apply after a restart).
[[nodiscard]] LiveReload apply_live_reload(const Config& running, const Config& fresh);

}  // namespace weedspray::daemon
