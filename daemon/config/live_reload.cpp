// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/live_reload.hpp"

#include <sstream>
#include <variant>

#include "daemon/config/config_schema.hpp"

namespace weedspray::daemon {
namespace {

// The live keys of `from` written into `target`.
Config with_live_keys_of(Config target, const Config& from) {
  target.spray = from.spray;
  target.alarms = from.alarms;
  target.pressure.setpoint_mpa = from.pressure.setpoint_mpa;
  target.daemon.log_level = from.daemon.log_level;
  target.daemon.autostart = from.daemon.autostart;
  target.daemon.status_max_rate_hz = from.daemon.status_max_rate_hz;
  return target;
}

}  // namespace

LiveReload apply_live_reload(const Config& running, const Config& fresh) {
  LiveReload reload;
  reload.restart_needed = dump_config(with_live_keys_of(fresh, running)) != dump_config(running);
  reload.config = with_live_keys_of(running, fresh);
  Config& merged = reload.config;
  Config kept = running;  // the accessors take non-const references
  Config reloaded = fresh;
  for (const auto& spec : config_keys()) {
    if (!is_safety_limit(spec.full_name())) continue;
    std::visit(
        [&](auto access) {
          if (access(reloaded) != access(kept)) reload.kept_limits.push_back(spec.full_name());
          access(merged) = access(kept);
        },
        spec.field);
  }
  if (merged.pressure.setpoint_mpa >= merged.alarms.over_pressure_mpa) {
    std::ostringstream message;
    message << "must be below the running alarms.over_pressure_mpa ("
            << merged.alarms.over_pressure_mpa << " MPa; a new trip takes a restart)";
    const auto source = fresh.sources.find("pressure.setpoint_mpa");
    throw ConfigError(
        source == fresh.sources.end() ? std::string("<defaults>") : source->second.file,
        source == fresh.sources.end() ? 0 : source->second.line, "pressure.setpoint_mpa",
        message.str());
  }
  return reload;
}

}  // namespace weedspray::daemon
