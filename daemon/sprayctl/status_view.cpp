// SPDX-License-Identifier: Apache-2.0
#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "daemon/sprayctl/value_text.hpp"
#include "daemon/sprayctl/views.hpp"

namespace weedspray::sprayctl {

namespace {

// Status as typed JSON: every property under its D-Bus name (numbers in the units of
// "units"; a structure as an object), with the time it was read.
void print_status_json(std::ostream& out, const Properties& p,
                       std::chrono::system_clock::time_point now) {
  Value status = Value::object();
  for (const auto& [name, value] : p) status[name] = value;
  status["timestamp"] = utc_timestamp(now);
  status["units"] = units_object();
  out << status.dump() << "\n";
}

}  // namespace

void print_status(std::ostream& out, const Properties& p, bool json,
                  std::chrono::system_clock::time_point now) {
  if (json) {
    print_status_json(out, p, now);
    return;
  }
  const auto get = [&](const char* name) {
    const auto found = p.find(name);
    return found == p.end() ? std::string("?") : text_value(name, found->second);
  };
  const auto is_true = [&](const char* name) {
    const auto found = p.find(name);
    return found != p.end() && found->second.is_boolean() && found->second.get<bool>();
  };
  // Degrees of latitude/longitude need 7 decimals (1 cm); altitude is the third value.
  const auto position = [&] {
    const auto found = p.find("Position");
    if (found == p.end() || !found->second.is_array() || found->second.size() != 3)
      return std::string("?");
    const Value& v = found->second;
    std::ostringstream text;
    const auto number = [](const Value& x) { return x.is_number() ? x.get<double>() : NAN; };
    text << std::fixed << std::setprecision(7) << number(v[0]) << ' ' << number(v[1])
         << std::setprecision(1) << ' ' << number(v[2]) << " m";
    return text.str();
  };
  // The rate means nothing while the machine stands (NaN, null in JSON).
  const auto rate = [&](const char* name) {
    const auto found = p.find(name);
    if (found == p.end() || !found->second.is_number()) return std::string("?");
    const double l_per_ha = found->second.get<double>();
    if (!std::isfinite(l_per_ha)) return std::string("- (standing)");
    std::ostringstream text;
    text << std::fixed << std::setprecision(1) << l_per_ha;
    return text.str();
  };
  // A receiver that is not configured has no position to show.
  const std::string gnss_line = get("GnssFix") == "off"
                                    ? std::string("GNSS:          off (gnss.enabled = false)\n")
                                    : "GNSS:          " + get("GnssFix") + " fix, position " +
                                          position() + ", " + get("GnssSpeed") + " m/s, course " +
                                          get("Course") + " deg, " + get("GnssSatellites") +
                                          " satellites, HDOP " + get("GnssHdop") + ", yaw rate " +
                                          get("YawRate") + " deg/s\n";
  out << "State:         " << get("State") << " (" << get("Mode") << ")\n"
      << "Pressure:      " << get("Pressure") << " MPa (set-point " << get("PressureSetpoint")
      << " MPa)\n"
      << "Flow:          " << get("Flow") << " L/min\n"
      << "Rate:          " << rate("ApplicationRate")
      << " L/ha now over the boom (dose at full weed cover " << rate("TargetRate") << " L/ha)\n"
      << "Tank:          " << get("TankLevel") << " %\n"
      << "Speed:         " << get("Speed") << " m/s (" << get("SpeedSource") << "), distance "
      << get("Distance") << " m\n"
      << "Nozzle duty:   " << get("NozzleDuty") << " %\n"
      << "Zone density:  " << get("ZoneDensity") << " (sprayed from " << get("DecisionThreshold")
      << ")\n"
      << "Nozzle health: " << get("NozzleHealth") << " (flow / baseline; none: off)\n"
      << "Flow trim:     x" << get("FlowTrim") << " on the nozzles' flows ("
      << (is_true("FlowTrimActive") ? "following the meter" : "held")
      << "); meter / calibrated nozzles " << get("MeteredOverCalibrated") << " (0: not yet known)\n"
      << "E-stop:        " << get("Estop") << "\n"
      << "Sprayed:       " << get("VolumeSprayed") << " L over " << get("AreaCovered")
      << " m^2, saving " << get("SavingsPercent") << " %\n"
      << "Vision:        " << get("FrameRate") << " fps, latency " << get("VisionLatencyMs")
      << " ms (p99 " << get("VisionLatencyP99Ms") << " ms)\n"
      << gnss_line << "Overruns:      " << get("ControlOverruns") << "\n"
      << "Calibration:   " << get("Calibration") << "\n"
      << "Flow meter:    " << get("MeterCalibration") << "\n"
      << "Alarms:        " << get("Alarms") << "\n";
  // Each latched alarm: its severity, whether its condition still holds, and what to do.
  const auto details = p.find("AlarmDetails");
  if (details != p.end() && details->second.is_array())
    for (const auto& alarm : details->second)
      out << "  - " << text_value("AlarmDetails", Value::array({alarm})) << "\n";
}

void print_event(std::ostream& out, const std::string& kind, const std::string& name,
                 const Value& value, bool json, std::chrono::system_clock::time_point now) {
  if (json) {
    Value event = {
        {"timestamp", utc_timestamp(now)}, {"event", kind}, {"name", name}, {"value", value}};
    if (*unit_of(name) != '\0') event["unit"] = unit_of(name);
    out << event.dump() << "\n";
    return;
  }
  out << local_time_of_day(now) << ' ';
  if (kind == "property") {
    out << name << " = " << text_value(name, value);
    if (*unit_of(name) != '\0') out << ' ' << unit_of(name);
    out << "\n";
  } else {
    out << kind << ": " << name << "\n";
  }
  out.flush();
}

}  // namespace weedspray::sprayctl
