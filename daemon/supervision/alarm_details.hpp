// SPDX-License-Identifier: Apache-2.0
// What one occurrence of an alarm measured, for its log entry (the catalog,
// alarm_catalog.cpp, holds what each alarm means and what to do), and how raised and cleared
// alarms are reported: the journal entry and the D-Bus signal.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "daemon/bus/dbus_service.hpp"
#include "daemon/config/config.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "daemon/supervision/alarms.hpp"

namespace weedspray::daemon {

// What the main loop measured when it evaluated the alarms.
struct AlarmMeasurements {
  const AlarmInputs& in;
  const PressureStatus& pressure;
  const ControlStatus& control;
  const Config& config;
  const Sprayer& sprayer;
  std::string output_failures;  // output_write_failed's message
  std::string vision_failures;  // vision_model_failed's message
  std::string exit_watcher_lost;
  bool wheel_wired = false;
  std::uint64_t overruns_last_second = 0;
  std::string timing_line;  // the loops' timing report, one line
  std::filesystem::path records_dir;
};

std::string alarm_detail(AlarmId id, const AlarmMeasurements& m);

// `bus` may be null (no D-Bus).
void report_alarms_raised(AlarmMask raised, const AlarmMeasurements& m, DbusService* bus);
// `why`: who cleared them, or why they cleared themselves.
void report_alarms_cleared(AlarmMask cleared, std::string_view why, DbusService* bus);

}  // namespace weedspray::daemon
