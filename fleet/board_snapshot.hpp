// SPDX-License-Identifier: Apache-2.0
// What the bridge knows of its board: the daemon's D-Bus properties it publishes, and the
// board's fixed description from the configuration. Turned into one JSON payload per topic.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace weedspray::fleet {

struct AlarmEntry {
  std::string name;
  std::string severity;  // fault | warning
  bool present = false;  // its condition still holds
  std::string remedy;    // what to do
};

// The daemon's properties, as last read (names as on D-Bus in the comments).
struct BoardSnapshot {
  std::string state = "Starting";  // State
  std::string mode;                // Mode
  double pressure_mpa = 0;         // Pressure
  double pressure_setpoint_mpa = 0;
  double flow_l_per_min = 0;
  double target_rate_l_per_ha = 0;  // TargetRate: the dose at full weed cover
  double tank_level_pct = 0;        // TankLevel
  double speed_m_per_s = 0;
  double distance_m = 0;
  std::string speed_source;             // SpeedSource
  std::vector<double> nozzle_duty_pct;  // NozzleDuty
  std::vector<double> zone_density;     // ZoneDensity
  double decision_threshold = 0;        // DecisionThreshold
  std::vector<double> nozzle_health;    // NozzleHealth (empty: [nozzle_health] off)
  std::vector<AlarmEntry> alarms;       // AlarmDetails
  double volume_sprayed_l = 0;
  double area_covered_m2 = 0;
  double savings_pct = 0;
  double frame_rate_hz = 0;
  double vision_latency_ms = 0;
  double vision_latency_p99_ms = 0;
  std::uint64_t control_overruns = 0;
  bool estop_circuit_closed = true;  // Estop
  bool estop_latched = false;
  std::string gnss_fix;  // GnssFix
};

// The board's place on the machine, from the configuration.
struct BoardInfo {
  std::string machine;
  std::string board;
  int nozzles = 0;
  double nozzle_width_m = 0;
  double first_nozzle_offset_m = 0;
  std::string commands;  // none | operator | admin
};

// The application rate over the sprayed width: flow / (speed x width), L/ha; 0 while the
// machine stands (below 0.05 m/s).
[[nodiscard]] double litres_per_hectare(double flow_l_per_min, double speed_m_per_s,
                                        double width_m);

// One payload per topic leaf (state, alarms, nozzles, pressure, flow, speed, tank, health,
// info), without the time stamp the publisher adds.
[[nodiscard]] std::map<std::string, nlohmann::json> board_payloads(const BoardSnapshot& snapshot,
                                                                   const BoardInfo& info);

}  // namespace weedspray::fleet
