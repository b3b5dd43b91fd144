// SPDX-License-Identifier: Apache-2.0
#include "fleet/board_snapshot.hpp"

namespace weedspray::fleet {

double litres_per_hectare(double flow_l_per_min, double speed_m_per_s, double width_m) {
  constexpr double kStandingSpeed = 0.05;  // m/s
  constexpr double kSquareMetresPerHectare = 10000;
  if (speed_m_per_s < kStandingSpeed || width_m <= 0) return 0;
  const double square_metres_per_min = speed_m_per_s * 60 * width_m;
  return flow_l_per_min / square_metres_per_min * kSquareMetresPerHectare;
}

std::map<std::string, nlohmann::json> board_payloads(const BoardSnapshot& s,
                                                     const BoardInfo& info) {
  using nlohmann::json;
  const double width_m = info.nozzles * info.nozzle_width_m;
  json alarms = json::array();
  for (const auto& alarm : s.alarms) {
    alarms.push_back({{"name", alarm.name},
                      {"severity", alarm.severity},
                      {"present", alarm.present},
                      {"remedy", alarm.remedy}});
  }
  return {
      {"state", {{"state", s.state}, {"mode", s.mode}}},
      {"alarms", {{"alarms", alarms}}},
      {"nozzles",
       {{"duty_pct", s.nozzle_duty_pct},
        {"weed_density", s.zone_density},
        {"decision_threshold", s.decision_threshold},
        {"health", s.nozzle_health}}},
      {"pressure", {{"mpa", s.pressure_mpa}, {"setpoint_mpa", s.pressure_setpoint_mpa}}},
      {"flow",
       {{"l_per_min", s.flow_l_per_min},
        {"l_per_ha", litres_per_hectare(s.flow_l_per_min, s.speed_m_per_s, width_m)},
        {"target_l_per_ha", s.target_rate_l_per_ha},
        {"volume_l", s.volume_sprayed_l},
        {"area_m2", s.area_covered_m2},
        {"savings_pct", s.savings_pct}}},
      {"speed",
       {{"m_per_s", s.speed_m_per_s},
        {"distance_m", s.distance_m},
        {"source", s.speed_source},
        {"gnss_fix", s.gnss_fix}}},
      {"tank", {{"level_pct", s.tank_level_pct}}},
      {"health",
       {{"frame_rate_hz", s.frame_rate_hz},
        {"vision_latency_ms", s.vision_latency_ms},
        {"vision_latency_p99_ms", s.vision_latency_p99_ms},
        {"control_overruns", s.control_overruns},
        {"estop_circuit_closed", s.estop_circuit_closed},
        {"estop_latched", s.estop_latched}}},
      {"info",
       {{"machine", info.machine},
        {"board", info.board},
        {"nozzles", info.nozzles},
        {"nozzle_width_m", info.nozzle_width_m},
        {"first_nozzle_offset_m", info.first_nozzle_offset_m},
        {"commands", info.commands}}},
  };
}

}  // namespace weedspray::fleet
