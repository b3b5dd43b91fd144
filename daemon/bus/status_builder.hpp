// SPDX-License-Identifier: Apache-2.0
// What fills the D-Bus status properties: one snapshot of the loops' published values, the
// state, the alarms, the totals and the calibrations (main thread).
#pragma once

#include <cstdint>

#include "daemon/backends/backends.hpp"
#include "daemon/bus/status.hpp"
#include "daemon/config/config.hpp"
#include "daemon/records/totals.hpp"
#include "daemon/sprayer/calibrations.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "daemon/supervision/alarms.hpp"
#include "daemon/supervision/state_machine.hpp"

namespace weedspray::daemon {

// What the snapshot is made of besides the loops' own status.
struct StatusSources {
  const Config& config;
  const Backends& backends;
  const Sprayer& sprayer;
  SprayerState state;
  double setpoint_mpa = 0;
  // The rate law's live settings (Operation): threshold, and nozzle flow at full weed cover.
  double decision_threshold = 0;
  double nominal_flow_l_per_min = 0;
  const AlarmEvaluator& alarms;
  Totals totals;
  double vision_latency_p99_ms = 0;
  std::uint64_t control_overruns = 0;
  const Calibrations* calibrations = nullptr;  // null before the run has them
};

Status build_status(const StatusSources& from, const PressureStatus& pressure,
                    const ControlStatus& control);

}  // namespace weedspray::daemon
