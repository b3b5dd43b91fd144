// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayctl/value_text.hpp"

#include <cmath>
#include <ctime>
#include <iomanip>
#include <sstream>
#include <string_view>
#include <utility>

namespace weedspray::sprayctl {

namespace {

// The properties that carry a unit; the others are states, names, counts or structures.
constexpr std::pair<std::string_view, const char*> kUnits[] = {
    {"Pressure", "MPa"},
    {"PressureSetpoint", "MPa"},
    {"Flow", "L/min"},
    {"TankLevel", "%"},
    {"Speed", "m/s"},
    {"Distance", "m"},
    {"NozzleDuty", "%"},
    {"ZoneDensity", "fraction of the zone"},
    {"VolumeSprayed", "L"},
    {"AreaCovered", "m^2"},
    {"SavingsPercent", "%"},
    {"ApplicationRate", "L/ha"},
    {"TargetRate", "L/ha"},
    {"FrameRate", "frames/s"},
    {"VisionLatencyMs", "ms"},
    {"VisionLatencyP99Ms", "ms"},
    {"Position", "deg, deg, m"},
    {"GnssSpeed", "m/s"},
    {"Course", "deg"},
    {"YawRate", "deg/s"},
    {"NozzleHealth", "flow / baseline"},
    {"FlowTrim", "factor"},
    {"MeteredOverCalibrated", "factor"},
};

// A reading that rounds to zero at three decimals prints as 0.000, not -0.000 (sensor noise).
double shown(double x) {
  return std::abs(x) < 0.0005 ? 0.0 : x;
}

std::string number_text(const Value& v, int decimals = 3) {
  std::ostringstream out;
  if (v.is_number_float()) {
    const double x = v.get<double>();
    out << std::fixed << std::setprecision(decimals) << (std::isfinite(x) ? shown(x) : x);
  } else {
    out << v.dump();
  }
  return out.str();
}

std::string meter_text(const Value& v) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(1) << v.value("pulses_per_litre", 0.0) << " pulses/L ("
       << v.value("source", "");
  if (v.value("source", "") == "calibration")
    text << "; configured " << v.value("configured_pulses_per_litre", 0.0) << ", its error "
         << std::setprecision(2) << v.value("configured_error_pct", 0.0) << " %";
  text << ")";
  return text.str();
}

std::string nozzle_line_text(const Value& v) {
  std::ostringstream text;
  text << "q = " << std::fixed << std::setprecision(5) << v.value("slope_l_per_min", 0.0) << " s + "
       << std::setprecision(4) << v.value("intercept_l_per_min", 0.0) << " L/min ("
       << v.value("source", "");
  const double r_squared = v.value("r_squared", 0.0);
  if (r_squared > 0) text << ", R^2 " << r_squared;
  text << ")";
  return text.str();
}

std::string alarm_text(const Value& v) {
  return v.value("name", "") + " (" + v.value("severity", "") + ", " +
         (v.value("present", false) ? "condition present" : "condition gone: clear-alarms") +
         "): " + v.value("remedy", "");
}

std::string estop_text(const Value& v) {
  std::ostringstream text;
  text << (v.value("circuit_closed", false) ? "circuit closed" : "circuit OPEN") << ", "
       << (v.value("latched", false) ? "LATCHED: valves closed, pump off" : "not latched");
  const double reaction_ms = v.value("last_reaction_ms", 0.0);
  if (reaction_ms > 0)
    text << "; last trip safe " << std::fixed << std::setprecision(3) << reaction_ms
         << " ms after the edge";
  return text.str();
}

std::string wheel_calibration_text(const Value& v) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(3) << "request " << v.value("request", 0) << ": "
       << v.value("state", "") << ", " << v.value("distance_m", 0.0) << " m, "
       << v.value("pulses", 0) << " pulses";
  if (v.value("state", "") == "done")
    text << ", " << v.value("pulses_per_metre", 0.0) << " pulses/m";
  return text.str();
}

std::string calibration_text(const Value& v) {
  std::ostringstream text;
  text << v.value("state", "") << " " << std::fixed << std::setprecision(0)
       << v.value("progress", 0.0) * 100 << " %: " << v.value("message", "");
  return text.str();
}

}  // namespace

const char* unit_of(const std::string& name) {
  for (const auto& [property, unit] : kUnits)
    if (property == name) return unit;
  return "";
}

Value units_object() {
  Value units = Value::object();
  for (const auto& [property, unit] : kUnits) units[std::string(property)] = unit;
  return units;
}

std::string text_value(const std::string& name, const Value& value) {
  if (name == "MeterCalibration") return meter_text(value);
  if (name == "Estop") return estop_text(value);
  if (name == "WheelCalibration") return wheel_calibration_text(value);
  if (name == "Calibration") return calibration_text(value);
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_number()) return number_text(value);
  if (value.is_array()) {
    // Lists of sentences (alarms, nozzle lines) are joined by commas; numbers by spaces.
    std::string text;
    for (std::size_t i = 0; i < value.size(); ++i) {
      const Value& item = value[i];
      const std::string separator = i == 0 ? "" : (item.is_number() ? " " : ", ");
      if (name == "AlarmDetails") {
        text += separator + alarm_text(item);
      } else if (name == "NozzleCalibration") {
        text += separator + nozzle_line_text(item);
      } else {
        text += separator + text_value("", item);
      }
    }
    // An empty list of measurements (all of which have units) is empty; of names, "none".
    return value.empty() && *unit_of(name) == '\0' ? "none" : text;
  }
  return value.dump();
}

namespace {

// `time` formatted by strftime's `format` in UTC or local time, then ".mmm".
std::string time_with_ms(std::chrono::system_clock::time_point time, bool utc, const char* format) {
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(time.time_since_epoch());
  const std::time_t seconds = static_cast<std::time_t>(ms.count() / 1000);
  std::tm broken_down{};
  if (utc) {
    gmtime_r(&seconds, &broken_down);
  } else {
    localtime_r(&seconds, &broken_down);
  }
  std::ostringstream out;
  out << std::put_time(&broken_down, format) << '.' << std::setw(3) << std::setfill('0')
      << ms.count() % 1000;
  return out.str();
}

}  // namespace

std::string utc_timestamp(std::chrono::system_clock::time_point time) {
  return time_with_ms(time, true, "%Y-%m-%dT%H:%M:%S") + 'Z';
}

std::string local_time_of_day(std::chrono::system_clock::time_point time) {
  return time_with_ms(time, false, "%H:%M:%S");
}

}  // namespace weedspray::sprayctl
