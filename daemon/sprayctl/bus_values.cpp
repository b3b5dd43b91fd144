// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayctl/bus_values.hpp"

#include <cstdlib>
#include <cstring>
#include <string_view>
#include <vector>

namespace weedspray::sprayctl {

void check(int r, const char* what) {
  if (r < 0) throw BusError{std::string(what) + ": " + std::strerror(-r)};
}

namespace {

// Reads the elements of an array of structures `element` (e.g. "(sddd)") with `read_one`,
// which returns false after the last.
template <typename ReadOne>
Value read_struct_array(sd_bus_message* m, const char* element, ReadOne read_one) {
  check(sd_bus_message_enter_container(m, 'a', element), "enter array");
  Value items = Value::array();
  while (true) {
    Value item;
    if (!read_one(item)) break;
    items.push_back(std::move(item));
  }
  check(sd_bus_message_exit_container(m), "exit array");
  return items;
}

Value read_contents(sd_bus_message* m, std::string_view sig) {
  if (sig == "s") {
    const char* s = nullptr;
    check(sd_bus_message_read(m, "s", &s), "read s");
    return s;
  }
  if (sig == "d") {
    double d = 0;
    check(sd_bus_message_read(m, "d", &d), "read d");
    return d;
  }
  if (sig == "t") {
    std::uint64_t t = 0;
    check(sd_bus_message_read(m, "t", &t), "read t");
    return t;
  }
  if (sig == "u") {
    std::uint32_t u = 0;
    check(sd_bus_message_read(m, "u", &u), "read u");
    return u;
  }
  if (sig == "b") {
    int b = 0;
    check(sd_bus_message_read(m, "b", &b), "read b");
    return b != 0;
  }
  if (sig == "(ddd)") {  // Position: latitude, longitude (degrees), altitude (m)
    double x[3] = {0, 0, 0};
    check(sd_bus_message_read(m, "(ddd)", &x[0], &x[1], &x[2]), "read (ddd)");
    return Value::array({x[0], x[1], x[2]});
  }
  if (sig == "(tsdtd)") {  // WheelCalibration
    std::uint64_t request = 0, pulses = 0;
    const char* state = nullptr;
    double metres = 0, per_metre = 0;
    check(sd_bus_message_read(m, "(tsdtd)", &request, &state, &metres, &pulses, &per_metre),
          "read (tsdtd)");
    return {{"request", request},
            {"state", state},
            {"distance_m", metres},
            {"pulses", pulses},
            {"pulses_per_metre", per_metre}};
  }
  if (sig == "(sds)") {  // Calibration: state, progress 0..1, message
    const char* state = nullptr;
    const char* message = nullptr;
    double progress = 0;
    check(sd_bus_message_read(m, "(sds)", &state, &progress, &message), "read (sds)");
    return {{"state", state}, {"progress", progress}, {"message", message}};
  }
  if (sig == "(bbd)") {  // Estop: circuit closed, latched, latest reaction
    int closed = 0, latched = 0;
    double reaction_ms = 0;
    check(sd_bus_message_read(m, "(bbd)", &closed, &latched, &reaction_ms), "read (bbd)");
    return {{"circuit_closed", closed != 0},
            {"latched", latched != 0},
            {"last_reaction_ms", reaction_ms}};
  }
  if (sig == "(sddd)") {  // MeterCalibration: source, K in use, configured K, its error
    const char* source = nullptr;
    double in_use = 0, configured = 0, error_pct = 0;
    check(sd_bus_message_read(m, "(sddd)", &source, &in_use, &configured, &error_pct),
          "read (sddd)");
    return {{"source", source},
            {"pulses_per_litre", in_use},
            {"configured_pulses_per_litre", configured},
            {"configured_error_pct", error_pct}};
  }
  if (sig == "a(ssbs)") {  // AlarmDetails: name, severity, condition present, remedy
    return read_struct_array(m, "(ssbs)", [&](Value& item) {
      const char* name = nullptr;
      const char* severity = nullptr;
      const char* remedy = nullptr;
      int present = 0;
      if (sd_bus_message_read(m, "(ssbs)", &name, &severity, &present, &remedy) <= 0) return false;
      item = {
          {"name", name}, {"severity", severity}, {"present", present != 0}, {"remedy", remedy}};
      return true;
    });
  }
  if (sig == "a(sds)") {  // RawInputs: name, value, unit
    return read_struct_array(m, "(sds)", [&](Value& item) {
      const char* name = nullptr;
      const char* unit = nullptr;
      double value = 0;
      if (sd_bus_message_read(m, "(sds)", &name, &value, &unit) <= 0) return false;
      item = {{"name", name}, {"value", value}, {"unit", unit}};
      return true;
    });
  }
  if (sig == "a(sddd)") {  // NozzleCalibration: each nozzle's line q = A s + b in use
    return read_struct_array(m, "(sddd)", [&](Value& item) {
      const char* source = nullptr;
      double slope = 0, intercept = 0, r_squared = 0;
      if (sd_bus_message_read(m, "(sddd)", &source, &slope, &intercept, &r_squared) <= 0)
        return false;
      item = {{"source", source},
              {"slope_l_per_min", slope},
              {"intercept_l_per_min", intercept},
              {"r_squared", r_squared}};
      return true;
    });
  }
  if (sig == "ad") {
    const void* data = nullptr;
    std::size_t size = 0;
    check(sd_bus_message_read_array(m, 'd', &data, &size), "read ad");
    const auto* doubles = static_cast<const double*>(data);
    return std::vector<double>(doubles, doubles + size / sizeof(double));
  }
  if (sig == "as") {
    char** strv = nullptr;
    check(sd_bus_message_read_strv(m, &strv), "read as");
    Value strings = Value::array();
    for (char** s = strv; s && *s; ++s) {
      strings.push_back(*s);
      free(*s);
    }
    free(strv);
    return strings;
  }
  check(sd_bus_message_skip(m, std::string(sig).c_str()), "skip");
  std::string unknown = "<";
  unknown += sig;
  unknown += '>';
  return unknown;
}

}  // namespace

Value read_variant(sd_bus_message* m) {
  char type = 0;
  const char* contents = nullptr;
  check(sd_bus_message_peek_type(m, &type, &contents), "peek");
  check(sd_bus_message_enter_container(m, 'v', contents), "variant");
  Value value = read_contents(m, contents);
  check(sd_bus_message_exit_container(m), "exit variant");
  return value;
}

Properties read_properties(sd_bus_message* m) {
  Properties properties;
  check(sd_bus_message_enter_container(m, 'a', "{sv}"), "enter a{sv}");
  while (true) {
    const int r = sd_bus_message_enter_container(m, 'e', "sv");
    check(r, "enter entry");
    if (r == 0) break;
    const char* name = nullptr;
    check(sd_bus_message_read(m, "s", &name), "read name");
    properties[name] = read_variant(m);
    check(sd_bus_message_exit_container(m), "exit entry");
  }
  check(sd_bus_message_exit_container(m), "exit a{sv}");
  return properties;
}

}  // namespace weedspray::sprayctl
