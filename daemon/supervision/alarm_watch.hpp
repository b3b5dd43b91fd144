// SPDX-License-Identifier: Apache-2.0
// The alarms judged each tick (main thread): the inputs gathered from the loops, the outputs,
// the exit watcher, the GNSS fix and the records; raised and cleared alarms reported; a fault
// puts the sprayer in Fault and stops the heartbeat; the lamp and buzzer show them.
#pragma once

#include <optional>

#include "daemon/backends/backends.hpp"
#include "daemon/backends/world_driver.hpp"
#include "daemon/bus/dbus_service.hpp"
#include "daemon/config/config.hpp"
#include "daemon/records/run_records.hpp"
#include "daemon/sprayer/ground_speed.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "daemon/supervision/alarms.hpp"
#include "daemon/supervision/exit_watch.hpp"
#include "daemon/supervision/loop_health.hpp"
#include "daemon/supervision/operation.hpp"
#include "daemon/supervision/output_checks.hpp"

namespace weedspray::daemon {

// What the alarms are judged from, and what they act on.
struct AlarmSources {
  const Config& config;
  Backends& backends;
  Sprayer& sprayer;
  const WorldDriver& world;
  Operation& operation;
  LoopHealth& loops;
  OutputChecks& outputs;
  ExitWatch& exit_watch;
  const RunRecords& records;
  DbusService* bus = nullptr;  // null: no D-Bus
};

class AlarmWatch {
 public:
  explicit AlarmWatch(const AlarmsSection& thresholds) : alarms_(thresholds) {}

  AlarmEvaluator& alarms() noexcept { return alarms_; }
  const AlarmEvaluator& alarms() const noexcept { return alarms_; }
  // From the loops' start (the GNSS fix's timeouts run from it).
  void start(Nanos start_time, const GnssSection& gnss);
  void evaluate(Nanos now, const PressureStatus& pressure, const ControlStatus& control,
                const AlarmSources& from);

 private:
  AlarmEvaluator alarms_;
  Nanos start_time_{};
  Nanos tank_last_ok_{};
  Nanos spraying_since_{};
  bool was_spraying_ = false;
  std::uint64_t coverage_gaps_seen_ = 0;
  std::optional<LostFixWatch> gnss_lost_fix_;  // from start() on
};

}  // namespace weedspray::daemon
