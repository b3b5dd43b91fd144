// SPDX-License-Identifier: Apache-2.0
// Faults injected into the simulated plant at a given time (weedsprayd --sim --sim-fault), so
// alarms and the fail-safe paths can be exercised end to end.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "daemon/supervision/output_write_watch.hpp"

namespace weedspray::sim::plant {
class HydraulicPlant;
}

namespace weedspray::daemon {

struct SimFault {
  std::string name;
  double at_s = 0;
  std::function<void(sim::plant::HydraulicPlant&)> apply;  // a fault of the plant, or
  // an output whose writes start failing with EIO ("pump_write_fail"), or work again
  // ("<output>_write_ok"): output_error is then EIO or 0.
  std::optional<OutputRole> output;
  int output_error = 0;
  int output_write_count = 0;  // "return_valve_write_fail_N": only its next N writes fail
  // A simulated device's fault: "camera_gone", "camera_back", "tank_silent", "tank_ok", and
  // the E-stop circuit opened ("estop_open": a pressed button or a cut wire) or closed again
  // ("estop_closed").
  std::string device;
};

// The names parse_sim_fault() knows, for help texts and the soak.
inline constexpr const char* kSimFaultNames =
    "sensor_open, sensor_short, sensor_ok, filter_blocked, filter_ok, tank_empty, tank_refill, "
    "nozzleN_blocked, nozzleN_blocked_PP (PP % blocked, 1..99), nozzleN_ok, "
    "meter_drift_PP / meter_drift_minus_PP (the meter's true K off by PP %, 1..30), "
    "nozzles_worn_PP (every tip PP % more flow, 1..50), valveN_stuck_open (opens whatever it "
    "is commanded), valveN_freed, camera_gone, "
    "camera_back, tank_silent, tank_ok, estop_open (the E-stop circuit opens), estop_closed; "
    "OUTPUT_write_fail / OUTPUT_write_ok with OUTPUT valve, pump, buzzer, led, heartbeat, "
    "return_valve; return_valve_write_fail_N (its next N writes fail, 1..99)";

// "sensor_open@5" -> the fault; nullopt for an unknown name or a malformed time.
std::optional<SimFault> parse_sim_fault(const std::string& text);

}  // namespace weedspray::daemon
