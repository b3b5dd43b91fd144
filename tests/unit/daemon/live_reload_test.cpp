// SPDX-License-Identifier: Apache-2.0
// A reload applies the live keys at once but keeps the running safety limits: a change to a
// trip limit waits for a restart, and a set-point above the running trip is refused.
#include "daemon/config/live_reload.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <type_traits>
#include <variant>

#include "daemon/config/config.hpp"
#include "daemon/config/config_schema.hpp"

namespace weedspray::daemon {
namespace {

Config parse(const std::string& text) {
  return load_config_from_strings({{"main.toml", text}});
}

bool kept(const LiveReload& reload, const std::string& key) {
  return std::find(reload.kept_limits.begin(), reload.kept_limits.end(), key) !=
         reload.kept_limits.end();
}

TEST(LiveReload, TripLimitsKeepTheirRunningValuesLiveKeysApply) {
  const Config running = default_config();
  const Config fresh = parse(
      "[alarms]\nover_pressure_mpa = 0.95\nsensor_fault_low_ma = 3.0\ntank_low_pct = 20\n"
      "[spray]\nduty_min_pct = 25\n[pressure]\nsetpoint_mpa = 0.3\n");
  const LiveReload reload = apply_live_reload(running, fresh);
  EXPECT_EQ(reload.config.alarms.over_pressure_mpa, running.alarms.over_pressure_mpa);
  EXPECT_EQ(reload.config.alarms.sensor_fault_low_ma, running.alarms.sensor_fault_low_ma);
  EXPECT_TRUE(kept(reload, "alarms.over_pressure_mpa"));
  EXPECT_TRUE(kept(reload, "alarms.sensor_fault_low_ma"));
  EXPECT_EQ(reload.kept_limits.size(), 2U);
  // A warning's level, the rate law and the set-point are live.
  EXPECT_EQ(reload.config.alarms.tank_low_pct, 20.0);
  EXPECT_EQ(reload.config.spray.duty_min_pct, 25.0);
  EXPECT_EQ(reload.config.pressure.setpoint_mpa, 0.3);
  EXPECT_FALSE(reload.restart_needed);
}

// Every safety limit, changed alone, is kept; and the limits include the pressure sensor's
// trips and each fault alarm's threshold.
TEST(LiveReload, EverySafetyLimitIsKept) {
  int limits = 0;
  for (const auto& spec : config_keys()) {
    if (!is_safety_limit(spec.full_name())) continue;
    ++limits;
    SCOPED_TRACE(spec.full_name());
    const Config running = default_config();
    Config fresh = default_config();
    std::visit(
        [&](auto access) {
          auto& value = access(fresh);
          using Value = std::remove_reference_t<decltype(value)>;
          if constexpr (std::is_same_v<Value, double> || std::is_same_v<Value, int>) {
            value = value == spec.max ? value - 1 : value + 1;
          } else {
            FAIL() << "a safety limit is a number";
          }
        },
        spec.field);
    const LiveReload reload = apply_live_reload(running, fresh);
    EXPECT_EQ(dump_config(reload.config), dump_config(running));
    EXPECT_TRUE(kept(reload, spec.full_name()));
  }
  for (const char* key :
       {"alarms.over_pressure_mpa", "alarms.sensor_fault_low_ma", "alarms.sensor_fault_high_ma",
        "alarms.sensor_fault_hold_s", "alarms.blocked_pressure_mpa", "alarms.no_flow_l_per_min",
        "alarms.tank_empty_pct", "alarms.camera_stall_s"}) {
    EXPECT_TRUE(is_safety_limit(key)) << key;
  }
  EXPECT_GE(limits, 8);
}

TEST(LiveReload, ASetPointAboveTheRunningTripIsRefused) {
  const Config running = default_config();  // trip 0.9 MPa
  const Config fresh = load_config_from_strings(
      {{"main.toml", "[boom]\nnozzles = 4\n"},
       {"conf.d/50-high.toml",
        "[pressure]\nsensor_max_mpa = 2.0\nsetpoint_mpa = 0.95\n[alarms]\nover_pressure_mpa = "
        "1.5\n"}});
  try {
    (void)apply_live_reload(running, fresh);
    FAIL() << "a set-point above the running trip was applied";
  } catch (const ConfigError& error) {
    EXPECT_EQ(error.key(), "pressure.setpoint_mpa");
    EXPECT_EQ(error.file(), "conf.d/50-high.toml");
    EXPECT_EQ(error.line(), 3);
  }
}

TEST(LiveReload, OtherChangesAreNamedForARestart) {
  const LiveReload reload = apply_live_reload(default_config(), parse("[pwm]\nfrequency_hz = 8\n"));
  EXPECT_TRUE(reload.restart_needed);
  EXPECT_EQ(reload.config.pwm.frequency_hz, default_config().pwm.frequency_hz);
  EXPECT_TRUE(reload.kept_limits.empty());
}

}  // namespace
}  // namespace weedspray::daemon
