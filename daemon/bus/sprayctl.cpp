// sprayctl: a small command-line client of weedsprayd over D-Bus (sd-bus).
//   sprayctl [--user] [--json] status|monitor|start|stop|set-pressure
//   MPA|alarms|clear-alarms|reload|snapshot [--camera N] OUT.png|calibrate-wheel [--distance M]
//   sprayctl calibrate meter --seconds S | --volume L    catch test, then the collected volume
//   sprayctl calibrate nozzles                            each nozzle's line over a duty sweep
//   sprayctl export-map ...   runs weedspray-export-map (no bus; GDAL stays out of sprayctl)
// Exit status: 0 done, 1 refused by the daemon or failed, 2 usage, 3 weedsprayd not reachable
// (docs/man/sprayctl.1.in).
#include <systemd/sd-bus.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "daemon/bus/dbus_names.hpp"

namespace {

using namespace weedspray::daemon;
using Value = std::variant<std::string, double, std::uint64_t, bool, std::vector<double>,
                           std::vector<std::string>>;
using Properties = std::map<std::string, Value>;

// Exit statuses, as sprayctl(1) documents them.
constexpr int kExitRefused = 1;      // the daemon refused the request, or it failed
constexpr int kExitUsage = 2;        // no command, an unknown one, a bad argument
constexpr int kExitUnreachable = 3;  // weedsprayd not on the bus, no bus, or no answer

struct BusError {
  std::string message;
  int exit_status = kExitRefused;
};

// Minimal JSON string escaping (the output has only flat values; no JSON library in the
// project's package list).
std::string json_string(const std::string& s) {
  std::ostringstream out;
  out << '"';
  for (const unsigned char c : s) {
    if (c == '"' || c == '\\') {
      out << '\\' << c;
    } else if (c < 0x20) {
      out << "\\u" << std::hex << std::setw(4) << std::setfill('0') << static_cast<int>(c)
          << std::dec;
    } else {
      out << c;
    }
  }
  out << '"';
  return out.str();
}

std::string json_value(const Value& value) {
  std::ostringstream out;
  out << std::setprecision(10);
  std::visit(
      [&](const auto& v) {
        using V = std::decay_t<decltype(v)>;
        // JSON has no NaN: a value not given (a GNSS field without a fix) is null.
        const auto number = [&](double x) {
          if (std::isfinite(x)) {
            out << x;
          } else {
            out << "null";
          }
        };
        if constexpr (std::is_same_v<V, std::string>) {
          out << json_string(v);
        } else if constexpr (std::is_same_v<V, bool>) {
          out << (v ? "true" : "false");
        } else if constexpr (std::is_same_v<V, double>) {
          number(v);
        } else if constexpr (std::is_same_v<V, std::vector<double>>) {
          out << '[';
          for (std::size_t i = 0; i < v.size(); ++i) {
            out << (i ? "," : "");
            number(v[i]);
          }
          out << ']';
        } else if constexpr (std::is_same_v<V, std::vector<std::string>>) {
          out << '[';
          for (std::size_t i = 0; i < v.size(); ++i) out << (i ? "," : "") << json_string(v[i]);
          out << ']';
        } else {
          out << v;
        }
      },
      value);
  return out.str();
}

// A reading that rounds to zero at three decimals prints as 0.000, not -0.000 (sensor noise).
double shown(double x) {
  return std::abs(x) < 0.0005 ? 0.0 : x;
}

std::string text_value(const Value& value) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3);
  std::visit(
      [&](const auto& v) {
        using V = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<V, std::vector<double>>) {
          for (std::size_t i = 0; i < v.size(); ++i) out << (i ? " " : "") << shown(v[i]);
        } else if constexpr (std::is_same_v<V, double>) {
          out << shown(v);
        } else if constexpr (std::is_same_v<V, std::vector<std::string>>) {
          for (std::size_t i = 0; i < v.size(); ++i) out << (i ? ", " : "") << v[i];
          if (v.empty()) out << "none";
        } else {
          out << v;
        }
      },
      value);
  return out.str();
}

void check(int r, const char* what) {
  if (r < 0) throw BusError{std::string(what) + ": " + std::strerror(-r)};
}

std::string meter_text(const char* source, double in_use, double configured, double error_pct) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(1) << in_use << " pulses/L (" << source;
  if (std::string_view(source) == "calibration")
    text << "; configured " << configured << ", its error " << std::setprecision(2) << error_pct
         << " %";
  text << ")";
  return text.str();
}

std::string line_text(const char* source, double slope, double intercept, double r_squared) {
  std::ostringstream text;
  text << "q = " << std::fixed << std::setprecision(5) << slope << " s + " << std::setprecision(4)
       << intercept << " L/min (" << source;
  if (r_squared > 0) text << ", R^2 " << r_squared;
  text << ")";
  return text.str();
}

// Reads one variant (of the types the service uses) from `m`.
Value read_variant(sd_bus_message* m) {
  char type = 0;
  const char* contents = nullptr;
  check(sd_bus_message_peek_type(m, &type, &contents), "peek");
  check(sd_bus_message_enter_container(m, 'v', contents), "variant");
  Value value;
  const std::string sig(contents);
  if (sig == "s") {
    const char* s = nullptr;
    check(sd_bus_message_read(m, "s", &s), "read s");
    value = std::string(s);
  } else if (sig == "d") {
    double d = 0;
    check(sd_bus_message_read(m, "d", &d), "read d");
    value = d;
  } else if (sig == "t") {
    std::uint64_t t = 0;
    check(sd_bus_message_read(m, "t", &t), "read t");
    value = t;
  } else if (sig == "u") {
    std::uint32_t u = 0;
    check(sd_bus_message_read(m, "u", &u), "read u");
    value = std::uint64_t{u};
  } else if (sig == "(ddd)") {  // Position: latitude, longitude, altitude
    double x[3] = {0, 0, 0};
    check(sd_bus_message_read(m, "(ddd)", &x[0], &x[1], &x[2]), "read (ddd)");
    value = std::vector<double>(x, x + 3);
  } else if (sig == "(tsdtd)") {  // WheelCalibration: request, state, metres, pulses, pulses/m
    std::uint64_t request = 0, pulses = 0;
    const char* state = nullptr;
    double metres = 0, per_metre = 0;
    check(sd_bus_message_read(m, "(tsdtd)", &request, &state, &metres, &pulses, &per_metre),
          "read (tsdtd)");
    std::ostringstream text;
    text << std::fixed << std::setprecision(3);
    text << "request " << request << ": " << state << ", " << metres << " m, " << pulses
         << " pulses";
    if (std::string_view(state) == "done") text << ", " << per_metre << " pulses/m";
    value = text.str();
  } else if (sig == "(sds)") {  // Calibration: state, progress, message
    const char* state = nullptr;
    const char* message = nullptr;
    double progress = 0;
    check(sd_bus_message_read(m, "(sds)", &state, &progress, &message), "read (sds)");
    std::ostringstream text;
    text << state << " " << std::fixed << std::setprecision(0) << progress * 100
         << " %: " << message;
    value = text.str();
  } else if (sig == "(bbd)") {  // Estop: circuit closed, latched, latest reaction (ms)
    int closed = 0, latched = 0;
    double reaction_ms = 0;
    check(sd_bus_message_read(m, "(bbd)", &closed, &latched, &reaction_ms), "read (bbd)");
    std::ostringstream text;
    text << (closed ? "circuit closed" : "circuit OPEN") << ", "
         << (latched ? "LATCHED: valves closed, pump off" : "not latched");
    if (reaction_ms > 0)
      text << "; last trip safe " << std::fixed << std::setprecision(3) << reaction_ms
           << " ms after the edge";
    value = text.str();
  } else if (sig == "(sddd)") {  // MeterCalibration: source, K in use, configured K, error
    const char* source = nullptr;
    double in_use = 0, configured = 0, error_pct = 0;
    check(sd_bus_message_read(m, "(sddd)", &source, &in_use, &configured, &error_pct),
          "read (sddd)");
    value = meter_text(source, in_use, configured, error_pct);
  } else if (sig == "a(ssbs)") {  // AlarmDetails: name, severity, present, remedy
    check(sd_bus_message_enter_container(m, 'a', "(ssbs)"), "enter a(ssbs)");
    std::vector<std::string> lines;
    const char* name = nullptr;
    const char* severity = nullptr;
    const char* remedy = nullptr;
    int present = 0;
    while (sd_bus_message_read(m, "(ssbs)", &name, &severity, &present, &remedy) > 0) {
      lines.push_back(std::string(name) + " (" + severity + ", " +
                      (present ? "condition present" : "condition gone: clear-alarms") +
                      "): " + remedy);
    }
    check(sd_bus_message_exit_container(m), "exit a(ssbs)");
    value = lines;
  } else if (sig == "a(sddd)") {  // NozzleCalibration: each nozzle's line in use
    check(sd_bus_message_enter_container(m, 'a', "(sddd)"), "enter a(sddd)");
    std::vector<std::string> lines;
    const char* source = nullptr;
    double slope = 0, intercept = 0, r_squared = 0;
    while (sd_bus_message_read(m, "(sddd)", &source, &slope, &intercept, &r_squared) > 0)
      lines.push_back(line_text(source, slope, intercept, r_squared));
    check(sd_bus_message_exit_container(m), "exit a(sddd)");
    value = lines;
  } else if (sig == "b") {
    int b = 0;
    check(sd_bus_message_read(m, "b", &b), "read b");
    value = b != 0;
  } else if (sig == "ad") {
    const void* data = nullptr;
    std::size_t size = 0;
    check(sd_bus_message_read_array(m, 'd', &data, &size), "read ad");
    const auto* doubles = static_cast<const double*>(data);
    value = std::vector<double>(doubles, doubles + size / sizeof(double));
  } else if (sig == "as") {
    char** strv = nullptr;
    check(sd_bus_message_read_strv(m, &strv), "read as");
    std::vector<std::string> strings;
    for (char** s = strv; s && *s; ++s) {
      strings.emplace_back(*s);
      free(*s);
    }
    free(strv);
    value = strings;
  } else {
    check(sd_bus_message_skip(m, contents), "skip");
    value = std::string("<" + sig + ">");
  }
  check(sd_bus_message_exit_container(m), "exit variant");
  return value;
}

// Reads an a{sv} dictionary.
Properties read_properties(sd_bus_message* m) {
  Properties properties;
  check(sd_bus_message_enter_container(m, 'a', "{sv}"), "enter a{sv}");
  while (true) {
    const int r = sd_bus_message_enter_container(m, 'e', "sv");
    check(r, "enter entry");
    if (r == 0) break;
    const char* name = nullptr;
    check(sd_bus_message_read(m, "s", &name), "read name");
    const std::string key(name);
    properties[key] = read_variant(m);
    check(sd_bus_message_exit_container(m), "exit entry");
  }
  check(sd_bus_message_exit_container(m), "exit a{sv}");
  return properties;
}

class Client {
 public:
  explicit Client(bool user_bus) : bus_kind_(user_bus ? "session" : "system") {
    const int r = user_bus ? sd_bus_open_user(&bus_) : sd_bus_open_system(&bus_);
    if (r < 0) throw unreachable_bus(r);
  }
  ~Client() { sd_bus_flush_close_unref(bus_); }

  Properties get_all() {
    sd_bus_error error = SD_BUS_ERROR_NULL;
    sd_bus_message* reply = nullptr;
    const int r = sd_bus_call_method(bus_, kBusName, kObjectPath, "org.freedesktop.DBus.Properties",
                                     "GetAll", &error, &reply, "s", kInterface);
    if (r < 0) fail(error, r);
    Properties properties = read_properties(reply);
    sd_bus_message_unref(reply);
    return properties;
  }

  void call(const char* method, const char* signature = "", double argument = 0) {
    sd_bus_error error = SD_BUS_ERROR_NULL;
    sd_bus_message* reply = nullptr;
    const int r = signature[0] == '\0'
                      ? sd_bus_call_method(bus_, kBusName, kObjectPath, kInterface, method, &error,
                                           &reply, "")
                      : sd_bus_call_method(bus_, kBusName, kObjectPath, kInterface, method, &error,
                                           &reply, signature, argument);
    if (r < 0) fail(error, r);
    sd_bus_message_unref(reply);
  }

  // Wheel calibration: starts one, returns its request number.
  std::uint64_t calibrate_wheel(double run_distance_m) {
    sd_bus_error error = SD_BUS_ERROR_NULL;
    sd_bus_message* reply = nullptr;
    const int r = sd_bus_call_method(bus_, kBusName, kObjectPath, kInterface, "CalibrateWheel",
                                     &error, &reply, "d", run_distance_m);
    if (r < 0) fail(error, r);
    std::uint64_t request = 0;
    const int read = sd_bus_message_read(reply, "t", &request);
    sd_bus_message_unref(reply);
    check(read, "read the request");
    return request;
  }

  struct WheelCalibration {
    std::uint64_t request = 0;
    std::string state;
    double distance_m = 0;
    std::uint64_t pulses = 0;
    double pulses_per_metre = 0;
  };
  WheelCalibration wheel_calibration() {
    sd_bus_error error = SD_BUS_ERROR_NULL;
    sd_bus_message* reply = nullptr;
    const int r = sd_bus_get_property(bus_, kBusName, kObjectPath, kInterface, "WheelCalibration",
                                      &error, &reply, "(tsdtd)");
    if (r < 0) fail(error, r);
    WheelCalibration c;
    const char* state = nullptr;
    const int read = sd_bus_message_read(reply, "(tsdtd)", &c.request, &state, &c.distance_m,
                                         &c.pulses, &c.pulses_per_metre);
    if (read >= 0) c.state = state;
    sd_bus_message_unref(reply);
    check(read, "read WheelCalibration");
    return c;
  }

  struct Calibration {
    std::string state;
    double progress = 0;
    std::string message;
  };
  Calibration calibration() {
    sd_bus_error error = SD_BUS_ERROR_NULL;
    sd_bus_message* reply = nullptr;
    const int r = sd_bus_get_property(bus_, kBusName, kObjectPath, kInterface, "Calibration",
                                      &error, &reply, "(sds)");
    if (r < 0) fail(error, r);
    Calibration c;
    const char* state = nullptr;
    const char* message = nullptr;
    const int read = sd_bus_message_read(reply, "(sds)", &state, &c.progress, &message);
    if (read >= 0) {
      c.state = state;
      c.message = message;
    }
    sd_bus_message_unref(reply);
    check(read, "read Calibration");
    return c;
  }

  // One property's value as `sprayctl status` shows it.
  std::string property_text(const char* name) {
    const Properties p = get_all();
    const auto found = p.find(name);
    return found == p.end() ? std::string("?") : text_value(found->second);
  }

  // The live view: camera `camera`'s next frame with its overlay, as PNG bytes.
  std::vector<std::uint8_t> snapshot(std::uint32_t camera) {
    sd_bus_error error = SD_BUS_ERROR_NULL;
    sd_bus_message* reply = nullptr;
    const int r = sd_bus_call_method(bus_, kBusName, kObjectPath, kInterface, "Snapshot", &error,
                                     &reply, "u", camera);
    if (r < 0) fail(error, r);
    const void* data = nullptr;
    std::size_t size = 0;
    const int read = sd_bus_message_read_array(reply, 'y', &data, &size);
    std::vector<std::uint8_t> png;
    if (read >= 0)
      png.assign(static_cast<const std::uint8_t*>(data),
                 static_cast<const std::uint8_t*>(data) + size);
    sd_bus_message_unref(reply);
    check(read, "read the PNG");
    return png;
  }

  int monitor(bool json) {
    const std::string match =
        std::string("type='signal',sender='") + kBusName + "',path='" + kObjectPath + "'";
    json_ = json;
    check(sd_bus_add_match(bus_, nullptr, match.c_str(), &Client::on_signal, this), "add match");
    static volatile std::sig_atomic_t stop = 0;
    std::signal(SIGINT, [](int) { stop = 1; });
    std::signal(SIGTERM, [](int) { stop = 1; });
    while (!stop) {
      const int r = sd_bus_process(bus_, nullptr);
      if (r < 0 && r != -EINTR) check(r, "process");
      if (r > 0) continue;
      const int w = sd_bus_wait(bus_, 500000);
      if (w < 0 && w != -EINTR) check(w, "wait");
    }
    return 0;
  }

 private:
  // A failed call: the daemon's own refusal keeps its error name and message; the bus saying
  // that nobody owns the name, or a connection that cannot be made, is "not reachable".
  [[noreturn]] void fail(sd_bus_error& error, int r) {
    const std::string name = error.name ? error.name : "";
    std::string message = error.message ? error.message : std::strerror(-r);
    sd_bus_error_free(&error);
    if (name == SD_BUS_ERROR_SERVICE_UNKNOWN || name == SD_BUS_ERROR_NAME_HAS_NO_OWNER) {
      throw BusError{std::string("weedsprayd is not running (no ") + kBusName + " on the " +
                         bus_kind_ + " bus)",
                     kExitUnreachable};
    }
    if (name == SD_BUS_ERROR_NO_REPLY || name == SD_BUS_ERROR_TIMEOUT || r == -ETIMEDOUT) {
      throw BusError{"weedsprayd did not answer: " + message, kExitUnreachable};
    }
    if (name.empty() && is_connection_error(r)) throw unreachable_bus(r);
    if (!name.empty()) message = name + ": " + message;
    throw BusError{message};
  }

  // sd-bus's errors for a bus that cannot be reached: no address (no session bus: ENOMEDIUM),
  // no socket, refused or dropped connection.
  static bool is_connection_error(int r) {
    for (const int e : {ENOMEDIUM, ENOENT, ECONNREFUSED, ECONNRESET, ENOTCONN, EPIPE, ENXIO})
      if (r == -e) return true;
    return false;
  }

  BusError unreachable_bus(int r) const {
    if (r == -ENOMEDIUM) {
      return BusError{"weedsprayd is not reachable: this shell has no " + bus_kind_ +
                          " bus (set DBUS_SESSION_BUS_ADDRESS to the bus weedsprayd --user is on)",
                      kExitUnreachable};
    }
    return BusError{"weedsprayd is not running (cannot connect to the " + bus_kind_ +
                        " bus: " + std::strerror(-r) + ")",
                    kExitUnreachable};
  }

  static int on_signal(sd_bus_message* m, void* userdata, sd_bus_error*) {
    auto& self = *static_cast<Client*>(userdata);
    const std::string member = sd_bus_message_get_member(m);
    if (member == "PropertiesChanged") {
      const char* interface = nullptr;
      if (sd_bus_message_read(m, "s", &interface) < 0) return 0;
      const Properties changed = read_properties(m);
      for (const auto& [name, value] : changed) self.print_event("property", name, value);
    } else if (member == "AlarmRaised" || member == "AlarmCleared") {
      const char* name = nullptr;
      if (sd_bus_message_read(m, "s", &name) < 0) return 0;
      self.print_event(member == "AlarmRaised" ? "alarm-raised" : "alarm-cleared", name,
                       std::string(name));
    }
    std::cout.flush();
    return 0;
  }

  std::string bus_kind_;

  void print_event(const std::string& kind, const std::string& name, const Value& value) {
    if (json_) {
      std::cout << "{\"event\":" << json_string(kind) << ",\"name\":" << json_string(name)
                << ",\"value\":" << json_value(value) << "}\n";
    } else if (kind == "property") {
      std::cout << name << " = " << text_value(value) << "\n";
    } else {
      std::cout << kind << ": " << name << "\n";
    }
  }

  sd_bus* bus_ = nullptr;
  bool json_ = false;
};

void print_status(const Properties& p, bool json) {
  if (json) {
    std::cout << '{';
    bool first = true;
    for (const auto& [name, value] : p) {
      std::cout << (first ? "" : ",") << json_string(name) << ':' << json_value(value);
      first = false;
    }
    std::cout << "}\n";
    return;
  }
  const auto get = [&](const char* name) {
    const auto found = p.find(name);
    return found == p.end() ? std::string("?") : text_value(found->second);
  };
  const auto is_true = [&](const char* name) {
    const auto found = p.find(name);
    const bool* b = found == p.end() ? nullptr : std::get_if<bool>(&found->second);
    return b != nullptr && *b;
  };
  // Degrees of latitude/longitude need 7 decimals (1 cm); altitude is the third value.
  const auto get_precise = [&](const char* name) {
    const auto found = p.find(name);
    const auto* v = found == p.end() ? nullptr : std::get_if<std::vector<double>>(&found->second);
    if (v == nullptr || v->size() != 3) return std::string("?");
    std::ostringstream out;
    out << std::fixed << std::setprecision(7) << (*v)[0] << ' ' << (*v)[1] << std::setprecision(1)
        << ' ' << (*v)[2] << " m";
    return out.str();
  };
  // A receiver that is not configured has no position to show.
  const std::string gnss_line =
      get("GnssFix") == "off"
          ? std::string("GNSS:          off (gnss.enabled = false)\n")
          : "GNSS:          " + get("GnssFix") + " fix, position " + get_precise("Position") +
                ", " + get("GnssSpeed") + " m/s, course " + get("Course") + " deg, " +
                get("GnssSatellites") + " satellites, HDOP " + get("GnssHdop") + ", yaw rate " +
                get("YawRate") + " deg/s\n";
  std::cout << "State:         " << get("State") << " (" << get("Mode") << ")\n"
            << "Pressure:      " << get("Pressure") << " MPa (set-point " << get("PressureSetpoint")
            << " MPa)\n"
            << "Flow:          " << get("Flow") << " L/min\n"
            << "Tank:          " << get("TankLevel") << " %\n"
            << "Speed:         " << get("Speed") << " m/s (" << get("SpeedSource") << "), distance "
            << get("Distance") << " m\n"
            << "Nozzle duty:   " << get("NozzleDuty") << " %\n"
            << "Zone density:  " << get("ZoneDensity") << "\n"
            << "Nozzle health: " << get("NozzleHealth") << " (flow / baseline; none: off)\n"
            << "Flow trim:     x" << get("FlowTrim") << " on the nozzles' flows ("
            << (is_true("FlowTrimActive") ? "following the meter" : "held")
            << "); meter / calibrated nozzles " << get("MeteredOverCalibrated")
            << " (0: not yet known)\n"
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
  const auto* lines =
      details == p.end() ? nullptr : std::get_if<std::vector<std::string>>(&details->second);
  if (lines != nullptr)
    for (const auto& line : *lines) std::cout << "  - " << line << "\n";
}

// Starts a calibration and follows it until done, printing each change of state.
int run_wheel_calibration(Client& client, double run_distance_m, double timeout_s) {
  const std::uint64_t request = client.calibrate_wheel(run_distance_m);
  std::cout << "wheel calibration " << request << ": drive straight for " << run_distance_m
            << " m at working speed\n"
            << std::flush;
  std::string last_state;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    const Client::WheelCalibration c = client.wheel_calibration();
    if (c.request == request) {
      if (c.state != last_state) {
        std::cout << "  " << c.state
                  << (c.state == "waiting" ? " (for a straight run at speed)" : "") << "\n"
                  << std::flush;
        last_state = c.state;
      }
      if (c.state == "done") {
        std::cout << std::fixed << std::setprecision(3) << c.pulses << " pulses over "
                  << c.distance_m << " m\n"
                  << "[wheel]\npulses_per_metre = " << c.pulses_per_metre << "\n";
        return 0;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  std::cerr << "sprayctl: calibrate-wheel: no straight run of " << run_distance_m << " m within "
            << timeout_s << " s (state " << (last_state.empty() ? "not started" : last_state)
            << ")\n";
  return kExitRefused;
}

// Follows the Calibration property until the run stops (done, cancelled or awaiting the
// catch test's volume), printing each new step; true when it ended as `wanted`.
bool follow_calibration(Client& client, const char* wanted, double timeout_s) {
  std::string last_message;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    const Client::Calibration c = client.calibration();
    if (c.message != last_message) {
      std::cout << "  [" << std::setw(3) << static_cast<int>(c.progress * 100) << " %] "
                << c.message << "\n"
                << std::flush;
      last_message = c.message;
    }
    if (c.state == "done" || c.state == "cancelled" || c.state == "awaiting_volume")
      return c.state == wanted;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  std::cerr << "sprayctl: calibrate: not finished within " << timeout_s << " s\n";
  return false;
}

int run_meter_calibration(Client& client, double catch_test_s, double volume_l) {
  if (volume_l > 0) {
    client.call("CalibrateMeter", "d", volume_l);
    std::cout << "flow meter: " << client.property_text("MeterCalibration") << "\n";
    return 0;
  }
  client.call("StartCatchTest", "d", catch_test_s);
  std::cout << "catch test: every valve open for " << catch_test_s
            << " s; collect the liquid of every nozzle\n"
            << std::flush;
  if (!follow_calibration(client, "awaiting_volume", catch_test_s + 30.0)) return kExitRefused;
  std::cout << "measure the collected litres, then: sprayctl calibrate meter --volume L\n";
  return 0;
}

int run_nozzle_calibration(Client& client, double timeout_s) {
  client.call("CalibrateNozzles");
  if (!follow_calibration(client, "done", timeout_s)) return kExitRefused;
  const Properties p = client.get_all();
  const auto found = p.find("NozzleCalibration");
  const auto* lines =
      found == p.end() ? nullptr : std::get_if<std::vector<std::string>>(&found->second);
  for (std::size_t i = 0; lines != nullptr && i < lines->size(); ++i)
    std::cout << "nozzle " << i << ": " << (*lines)[i] << "\n";
  return 0;
}

}  // namespace

// Replaces this process with weedspray-export-map: the one beside sprayctl (an install's bin
// folder, or the build tree's daemon/), else the first on PATH. Returns only on failure.
int exec_export_map(const std::vector<std::string>& args) {
  std::vector<std::string> argv_strings{"weedspray-export-map"};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv_c;
  for (auto& a : argv_strings) argv_c.push_back(a.data());
  argv_c.push_back(nullptr);
  char self[4096];
  const ssize_t n = ::readlink("/proc/self/exe", self, sizeof self - 1);
  if (n > 0) {
    std::string beside(self, static_cast<std::size_t>(n));
    beside = beside.substr(0, beside.rfind('/') + 1) + "weedspray-export-map";
    if (::access(beside.c_str(), X_OK) == 0) ::execv(beside.c_str(), argv_c.data());
  }
  ::execvp("weedspray-export-map", argv_c.data());
  std::cerr << "sprayctl: cannot run weedspray-export-map: " << std::strerror(errno)
            << " (it is built where GDAL is: not in the arm64 build; export on a PC from a copy "
               "of the as-applied log folder)\n";
  return 1;
}

int main(int argc, char** argv) {
  CLI::App app{"sprayctl: status and control of weedsprayd over D-Bus"};
  bool user_bus = false;
  bool json = false;
  double pressure_mpa = 0;
  app.add_flag("--user", user_bus, "use the session bus (weedsprayd --user)");
  app.add_flag("--json", json, "machine-readable output (one JSON object per line)");
  app.set_version_flag("--version", std::string("sprayctl ") + WEEDSPRAY_VERSION);
  app.require_subcommand(1);
  auto* status = app.add_subcommand("status", "show the sprayer's state and measurements");
  auto* monitor = app.add_subcommand("monitor", "print property changes and alarms until Ctrl-C");
  auto* start = app.add_subcommand("start", "start spraying");
  auto* stop = app.add_subcommand("stop", "stop spraying (valves closed, pump held)");
  auto* set_pressure = app.add_subcommand("set-pressure", "change the pressure set-point");
  set_pressure->add_option("MPA", pressure_mpa, "set-point in MPa")->required();
  auto* alarms = app.add_subcommand("alarms", "list latched alarms");
  auto* clear_alarms = app.add_subcommand("clear-alarms", "clear latched alarms (leaves Fault)");
  auto* reload = app.add_subcommand("reload", "re-read the configuration");
  auto* snapshot = app.add_subcommand(
      "snapshot",
      "save a camera's latest frame with the weed/crop overlay, zone grid, densities "
      "and duties as a PNG (at most 2 a second)");
  std::uint32_t camera = 0;
  std::string snapshot_path;
  snapshot->add_option("--camera", camera, "camera index (0 = the first [[camera]])");
  snapshot->add_option("OUT", snapshot_path, "PNG file to write")->required();
  auto* calibrate_wheel = app.add_subcommand(
      "calibrate-wheel",
      "measure the wheel sensor's pulses per metre with the GNSS receiver: drive straight at a "
      "steady working speed; a turn or a stop starts the run again. Prints the value for "
      "wheel.pulses_per_metre");
  double run_distance_m = 100.0;
  double calibration_timeout_s = 600.0;
  calibrate_wheel->add_option("--distance", run_distance_m, "straight run, metres (10..5000)")
      ->capture_default_str();
  calibrate_wheel->add_option("--timeout", calibration_timeout_s, "give up after, seconds")
      ->capture_default_str();
  auto* calibrate = app.add_subcommand(
      "calibrate", "calibrate the flow meter or the nozzles (in Idle: pump on, not spraying)");
  calibrate->require_subcommand(1);
  auto* calibrate_meter = calibrate->add_subcommand(
      "meter",
      "catch test: --seconds S opens every valve for S s at the set-point (collect all the "
      "liquid); then --volume L enters the litres collected. The meter's pulses per litre is "
      "stored in the state directory and used instead of flow.pulses_per_litre");
  double catch_test_s = 0;
  double collected_l = 0;
  auto* seconds_option =
      calibrate_meter->add_option("--seconds", catch_test_s, "catch test length, s (1..600)");
  calibrate_meter->add_option("--volume", collected_l, "litres collected in the catch test")
      ->excludes(seconds_option);
  auto* calibrate_nozzles = calibrate->add_subcommand(
      "nozzles",
      "each nozzle alone over calibration.duties_pct at the set-point and PWM frequency, its "
      "flow from the line meter: each nozzle's line q = A s + b, stored in the state directory "
      "and used by the rate law (the [spray] line stays for a fit below "
      "calibration.min_r_squared)");
  double nozzle_timeout_s = 600.0;
  calibrate_nozzles->add_option("--timeout", nozzle_timeout_s, "give up after, seconds")
      ->capture_default_str();
  auto* export_map = app.add_subcommand(
      "export-map",
      "the as-applied log as a map a GIS opens: export-map [--from T] [--to T] --format "
      "geojson|gpkg|shp [--dir LOGDIR] [--config FILE] OUT (runs weedspray-export-map; "
      "`sprayctl export-map --help` lists its options)");
  // Every argument after export-map, --help included, is the exporter's.
  export_map->prefix_command();
  export_map->set_help_flag();
  for (auto* sub : {status, monitor, alarms}) sub->add_flag("--json", json, "JSON output");
  // A bare `sprayctl` prints its usage; usage errors exit with their own status (CLI11's
  // default, 106 and up, says nothing to a script).
  app.name("sprayctl");
  if (argc == 1) {
    std::cerr << app.help();
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int status = app.exit(error);
    return status == 0 ? 0 : kExitUsage;
  }
  if (*export_map) return exec_export_map(export_map->remaining());
  if (*calibrate_meter && !(catch_test_s > 0) && !(collected_l > 0)) {
    std::cerr << "sprayctl: calibrate meter: --seconds S (start the catch test) or --volume L\n";
    return kExitUsage;
  }

  try {
    Client client(user_bus);
    if (*status) {
      print_status(client.get_all(), json);
    } else if (*monitor) {
      return client.monitor(json);
    } else if (*start) {
      client.call("Start");
    } else if (*stop) {
      client.call("Stop");
    } else if (*set_pressure) {
      client.call("SetPressureSetpoint", "d", pressure_mpa);
    } else if (*alarms) {
      const Properties p = client.get_all();
      const auto found = p.find("Alarms");
      if (found == p.end()) throw BusError{"no Alarms property"};
      std::cout << (json ? "{\"Alarms\":" + json_value(found->second) + "}"
                         : text_value(found->second))
                << "\n";
    } else if (*clear_alarms) {
      client.call("ClearAlarms");
    } else if (*reload) {
      client.call("ReloadConfig");
    } else if (*calibrate_meter) {
      return run_meter_calibration(client, catch_test_s, collected_l);
    } else if (*calibrate_nozzles) {
      return run_nozzle_calibration(client, nozzle_timeout_s);
    } else if (*calibrate_wheel) {
      return run_wheel_calibration(client, run_distance_m, calibration_timeout_s);
    } else if (*snapshot) {
      // Written here, by the operator's own process: the daemon runs as user weedspray and
      // never writes where a caller asks.
      const std::vector<std::uint8_t> png = client.snapshot(camera);
      std::ofstream out(snapshot_path, std::ios::binary | std::ios::trunc);
      out.write(reinterpret_cast<const char*>(png.data()),
                static_cast<std::streamsize>(png.size()));
      out.close();
      if (!out) throw BusError{"cannot write " + snapshot_path + ": " + std::strerror(errno)};
      std::cout << snapshot_path << ": " << png.size() << " bytes (camera " << camera << ")\n";
    }
  } catch (const BusError& error) {
    std::cerr << "sprayctl: " << error.message << "\n";
    return error.exit_status;
  }
  return 0;
}
