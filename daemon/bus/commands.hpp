// SPDX-License-Identifier: Apache-2.0
// What the org.weedspray.Sprayer1 methods do (main thread): each command checked, then handed
// to what it acts on (the operation, the alarms, the reloads, the live view, the sprayer's
// wheel calibration, the simulated world).
#pragma once

#include <functional>

#include "daemon/backends/backends.hpp"
#include "daemon/backends/world_driver.hpp"
#include "daemon/bus/dbus_service.hpp"
#include "daemon/config/config.hpp"
#include "daemon/config/config_reloads.hpp"
#include "daemon/sprayer/live_view.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "daemon/supervision/alarms.hpp"
#include "daemon/supervision/operation.hpp"

namespace weedspray::daemon {

// What the commands act on; the sprayer and the live view come once the loops are built.
struct CommandTargets {
  const Config& config;
  const Backends& backends;
  Operation& operation;
  AlarmEvaluator& alarms;
  ConfigReloads& reloads;
  WorldDriver& world;
  std::function<void()> stop_now;  // ends the run with a failure (the bus is lost)
};

class Commands final : public CommandHandler {
 public:
  explicit Commands(CommandTargets targets) : to_(std::move(targets)) {}

  void attach(Sprayer& sprayer, LiveView& live_view) noexcept {
    sprayer_ = &sprayer;
    live_view_ = &live_view;
  }
  // Where AlarmCleared is signalled (null: no D-Bus).
  void set_bus(DbusService* bus) noexcept { bus_ = bus; }

  CommandResult start() override { return to_.operation.start(); }
  CommandResult stop() override { return to_.operation.stop(); }
  CommandResult set_pressure_setpoint(double mpa) override;
  CommandResult set_decision_threshold(double threshold) override;
  CommandResult set_target_rate(double l_per_ha) override;
  CommandResult reload_config(ReloadReply reply) override;
  CommandResult clear_alarms() override;
  CommandResult inject_sim_fault(const std::string& name) override;
  CommandResult snapshot(std::uint32_t camera, SnapshotReply reply) override;
  CommandResult calibrate_wheel(double run_distance_m, std::uint64_t& request) override;
  CommandResult start_catch_test(double seconds) override;
  CommandResult calibrate_meter(double volume_l) override;
  CommandResult calibrate_nozzles() override;
  CommandResult test_valve(std::uint32_t nozzle, double duty_pct, double seconds) override;
  CommandResult test_pump(double seconds) override;
  CommandResult motion(double& speed_m_per_s, double& distance_m, std::uint64_t& time_ns,
                       SharedFix& fix) override;
  CommandResult feed_shared_motion(double speed_m_per_s, double distance_m,
                                   std::uint64_t sender_time_ns, const SharedFix& fix) override;
  void bus_lost() override;

 private:
  // A calibration's command, and its valves to the loops when it was taken.
  CommandResult calibration_command(const std::function<CommandResult(Calibrations&)>& command);

  CommandTargets to_;
  Sprayer* sprayer_ = nullptr;
  LiveView* live_view_ = nullptr;
  DbusService* bus_ = nullptr;
};

}  // namespace weedspray::daemon
