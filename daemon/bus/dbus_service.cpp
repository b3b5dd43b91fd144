// SPDX-License-Identifier: Apache-2.0
#include "daemon/bus/dbus_service.hpp"

#include <cerrno>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "daemon/bus/dbus_names.hpp"

namespace weedspray::daemon {
namespace {

constexpr auto kEmits = SD_BUS_VTABLE_PROPERTY_EMITS_CHANGE;
// The bus policy (systemd/org.weedspray.Sprayer1.conf) decides who may call methods; sd-bus's
// own CAP_SYS_ADMIN check is switched off so members of group weedspray can.
constexpr auto kMethodFlags = SD_BUS_VTABLE_UNPRIVILEGED;

#define WS_PROPERTY(name, signature) \
  SD_BUS_PROPERTY(name, signature, DbusService::get_property, 0, kEmits)
#define WS_METHOD(name, signature, in_names, result, out_names)                               \
  SD_BUS_METHOD_WITH_NAMES(name, signature, in_names, result, out_names, DbusService::method, \
                           kMethodFlags)

std::runtime_error bus_error(const char* what, int r) {
  return std::runtime_error(std::string(what) + ": " + std::strerror(-r));
}

int append_doubles(sd_bus_message* reply, const std::vector<double>& values) {
  return sd_bus_message_append_array(reply, 'd', values.data(), values.size() * sizeof(double));
}

int append_strings(sd_bus_message* reply, const std::vector<std::string>& values) {
  int r = sd_bus_message_open_container(reply, 'a', "s");
  for (const auto& value : values) {
    if (r >= 0) r = sd_bus_message_append(reply, "s", value.c_str());
  }
  return r < 0 ? r : sd_bus_message_close_container(reply);
}

// Names of properties whose value differs between two snapshots.
std::vector<const char*> changed_properties(const Status& a, const Status& b) {
  std::vector<const char*> names;
  const auto check = [&](bool differs, const char* name) {
    if (differs) names.push_back(name);
  };
  // NaN (not given) compares unequal to itself: only a change to or from a value counts.
  const auto differs = [](double x, double y) { return !(x == y || (x != x && y != y)); };
  check(a.state != b.state, "State");
  check(a.pressure_mpa != b.pressure_mpa, "Pressure");
  check(a.pressure_setpoint_mpa != b.pressure_setpoint_mpa, "PressureSetpoint");
  check(a.decision_threshold != b.decision_threshold, "DecisionThreshold");
  check(a.flow_l_per_min != b.flow_l_per_min, "Flow");
  check(a.tank_level_pct != b.tank_level_pct, "TankLevel");
  check(a.speed_m_per_s != b.speed_m_per_s, "Speed");
  check(a.distance_m != b.distance_m, "Distance");
  check(a.nozzle_duty_pct != b.nozzle_duty_pct, "NozzleDuty");
  check(a.zone_density != b.zone_density, "ZoneDensity");
  check(a.alarms != b.alarms, "Alarms");
  check(a.alarm_details != b.alarm_details, "AlarmDetails");
  check(a.volume_sprayed_l != b.volume_sprayed_l, "VolumeSprayed");
  check(a.area_covered_m2 != b.area_covered_m2, "AreaCovered");
  check(a.savings_pct != b.savings_pct, "SavingsPercent");
  check(differs(a.application_rate_l_per_ha, b.application_rate_l_per_ha), "ApplicationRate");
  check(a.target_rate_l_per_ha != b.target_rate_l_per_ha, "TargetRate");
  check(a.frame_rate_hz != b.frame_rate_hz, "FrameRate");
  check(a.vision_latency_ms != b.vision_latency_ms, "VisionLatencyMs");
  check(a.vision_latency_p99_ms != b.vision_latency_p99_ms, "VisionLatencyP99Ms");
  check(a.control_overruns != b.control_overruns, "ControlOverruns");
  check(a.mode != b.mode, "Mode");
  check(a.speed_source != b.speed_source, "SpeedSource");
  check(a.gnss_fix != b.gnss_fix, "GnssFix");
  check(differs(a.latitude_deg, b.latitude_deg) || differs(a.longitude_deg, b.longitude_deg) ||
            differs(a.altitude_m, b.altitude_m),
        "Position");
  check(differs(a.gnss_speed_m_per_s, b.gnss_speed_m_per_s), "GnssSpeed");
  check(differs(a.course_deg, b.course_deg), "Course");
  check(differs(a.gnss_hdop, b.gnss_hdop), "GnssHdop");
  check(a.gnss_satellites != b.gnss_satellites, "GnssSatellites");
  check(a.gnss_utc != b.gnss_utc, "GnssTime");
  check(a.yaw_rate_deg_per_s != b.yaw_rate_deg_per_s, "YawRate");
  check(a.wheel_calibration_request != b.wheel_calibration_request ||
            a.wheel_calibration_state != b.wheel_calibration_state ||
            a.wheel_calibration_distance_m != b.wheel_calibration_distance_m ||
            a.wheel_calibration_pulses != b.wheel_calibration_pulses ||
            a.wheel_calibration_pulses_per_metre != b.wheel_calibration_pulses_per_metre,
        "WheelCalibration");
  check(a.calibration_state != b.calibration_state ||
            a.calibration_progress != b.calibration_progress ||
            a.calibration_message != b.calibration_message,
        "Calibration");
  check(a.meter_source != b.meter_source || a.meter_pulses_per_litre != b.meter_pulses_per_litre ||
            a.meter_configured_pulses_per_litre != b.meter_configured_pulses_per_litre ||
            a.meter_error_pct != b.meter_error_pct,
        "MeterCalibration");
  check(a.nozzle_lines != b.nozzle_lines, "NozzleCalibration");
  check(a.nozzle_flow_ratio != b.nozzle_flow_ratio, "NozzleHealth");
  check(a.flow_trim_correction != b.flow_trim_correction, "FlowTrim");
  check(a.flow_trim_active != b.flow_trim_active, "FlowTrimActive");
  check(a.calibration_ratio != b.calibration_ratio, "MeteredOverCalibrated");
  check(a.estop_circuit_closed != b.estop_circuit_closed || a.estop_latched != b.estop_latched ||
            a.estop_reaction_ms != b.estop_reaction_ms,
        "Estop");
  return names;
}

const sd_bus_vtable kVtable[] = {
    SD_BUS_VTABLE_START(0),
    WS_PROPERTY("State", "s"),
    WS_PROPERTY("Pressure", "d"),
    WS_PROPERTY("PressureSetpoint", "d"),
    WS_PROPERTY("DecisionThreshold", "d"),
    WS_PROPERTY("Flow", "d"),
    WS_PROPERTY("TankLevel", "d"),
    WS_PROPERTY("Speed", "d"),
    WS_PROPERTY("Distance", "d"),
    WS_PROPERTY("NozzleDuty", "ad"),
    WS_PROPERTY("ZoneDensity", "ad"),
    WS_PROPERTY("Alarms", "as"),
    WS_PROPERTY("AlarmDetails", "a(ssbs)"),
    WS_PROPERTY("VolumeSprayed", "d"),
    WS_PROPERTY("AreaCovered", "d"),
    WS_PROPERTY("SavingsPercent", "d"),
    WS_PROPERTY("ApplicationRate", "d"),
    WS_PROPERTY("TargetRate", "d"),
    WS_PROPERTY("FrameRate", "d"),
    WS_PROPERTY("VisionLatencyMs", "d"),
    WS_PROPERTY("VisionLatencyP99Ms", "d"),
    WS_PROPERTY("ControlOverruns", "t"),
    // Read on request only: counts and currents change every tick, no signal for each.
    SD_BUS_PROPERTY("RawInputs", "a(sds)", DbusService::get_property, 0, 0),
    WS_PROPERTY("Mode", "s"),
    WS_PROPERTY("SpeedSource", "s"),
    WS_PROPERTY("GnssFix", "s"),
    WS_PROPERTY("Position", "(ddd)"),
    WS_PROPERTY("GnssSpeed", "d"),
    WS_PROPERTY("Course", "d"),
    WS_PROPERTY("GnssHdop", "d"),
    WS_PROPERTY("GnssSatellites", "u"),
    WS_PROPERTY("GnssTime", "s"),
    WS_PROPERTY("YawRate", "d"),
    WS_PROPERTY("WheelCalibration", "(tsdtd)"),
    WS_PROPERTY("Calibration", "(sds)"),
    WS_PROPERTY("MeterCalibration", "(sddd)"),
    WS_PROPERTY("NozzleCalibration", "a(sddd)"),
    WS_PROPERTY("NozzleHealth", "ad"),
    WS_PROPERTY("FlowTrim", "d"),
    WS_PROPERTY("FlowTrimActive", "b"),
    WS_PROPERTY("MeteredOverCalibrated", "d"),
    WS_PROPERTY("Estop", "(bbd)"),
    WS_METHOD("Start", "", "", "", ""),
    WS_METHOD("Stop", "", "", "", ""),
    // Arguments named, so the interface's introspection (and the shipped XML) says what each is.
    WS_METHOD("SetPressureSetpoint", "d", SD_BUS_PARAM(mpa), "", ""),
    WS_METHOD("SetDecisionThreshold", "d", SD_BUS_PARAM(threshold), "", ""),
    WS_METHOD("SetTargetRate", "d", SD_BUS_PARAM(l_per_ha), "", ""),
    WS_METHOD("ReloadConfig", "", "", "", ""),
    WS_METHOD("ClearAlarms", "", "", "", ""),
    WS_METHOD("InjectSimFault", "s", SD_BUS_PARAM(fault), "", ""),
    WS_METHOD("Snapshot", "u", SD_BUS_PARAM(camera), "ay", SD_BUS_PARAM(png)),
    WS_METHOD("CalibrateWheel", "d", SD_BUS_PARAM(metres), "t", SD_BUS_PARAM(request)),
    WS_METHOD("StartCatchTest", "d", SD_BUS_PARAM(seconds), "", ""),
    WS_METHOD("CalibrateMeter", "d", SD_BUS_PARAM(litres), "", ""),
    WS_METHOD("CalibrateNozzles", "", "", "", ""),
    WS_METHOD("TestValve", "udd", SD_BUS_PARAM(nozzle) SD_BUS_PARAM(duty_pct) SD_BUS_PARAM(seconds),
              "", ""),
    WS_METHOD("TestPump", "d", SD_BUS_PARAM(seconds), "", ""),
    WS_METHOD("Motion", "", "", "ddt",
              SD_BUS_PARAM(speed_m_per_s) SD_BUS_PARAM(distance_m) SD_BUS_PARAM(time_ns)),
    WS_METHOD("FeedSharedMotion", "ddt",
              SD_BUS_PARAM(speed_m_per_s) SD_BUS_PARAM(distance_m) SD_BUS_PARAM(sender_time_ns), "",
              ""),
    WS_METHOD("MotionWithFix", "", "", "ddtdddutx",
              SD_BUS_PARAM(speed_m_per_s) SD_BUS_PARAM(distance_m) SD_BUS_PARAM(time_ns)
                  SD_BUS_PARAM(latitude_deg) SD_BUS_PARAM(longitude_deg) SD_BUS_PARAM(heading_deg)
                      SD_BUS_PARAM(fix_mode) SD_BUS_PARAM(fix_time_ns) SD_BUS_PARAM(fix_utc_ns)),
    WS_METHOD("FeedSharedMotionWithFix", "ddtdddutx",
              SD_BUS_PARAM(speed_m_per_s) SD_BUS_PARAM(distance_m) SD_BUS_PARAM(sender_time_ns)
                  SD_BUS_PARAM(latitude_deg) SD_BUS_PARAM(longitude_deg) SD_BUS_PARAM(heading_deg)
                      SD_BUS_PARAM(fix_mode) SD_BUS_PARAM(fix_time_ns) SD_BUS_PARAM(fix_utc_ns),
              "", ""),
    SD_BUS_SIGNAL_WITH_NAMES("AlarmRaised", "s", SD_BUS_PARAM(alarm), 0),
    SD_BUS_SIGNAL_WITH_NAMES("AlarmCleared", "s", SD_BUS_PARAM(alarm), 0),
    SD_BUS_VTABLE_END,
};

}  // namespace

DbusService::DbusService(sd_event* event, bool user_bus, CommandHandler& handler)
    : handler_(handler) {
  int r = user_bus ? sd_bus_open_user(&bus_) : sd_bus_open_system(&bus_);
  if (r < 0)
    throw bus_error(
        user_bus ? "cannot connect to the session bus" : "cannot connect to the system bus", r);
  r = sd_bus_add_object_vtable(bus_, &slot_, kObjectPath, kInterface, kVtable, this);
  if (r < 0) throw bus_error("cannot register the D-Bus object", r);
  r = sd_bus_request_name(bus_, kBusName, 0);
  if (r < 0) throw bus_error("cannot own the name org.weedspray.Sprayer1", r);
  // sd-bus reports a closed connection as this local signal (sd_bus_set_exit_on_disconnect
  // would end the event loop without telling the daemon why).
  r = sd_bus_match_signal(bus_, &disconnected_slot_, nullptr, "/org/freedesktop/DBus/Local",
                          "org.freedesktop.DBus.Local", "Disconnected",
                          &DbusService::on_disconnected, this);
  if (r < 0) throw bus_error("cannot watch the bus connection", r);
  r = sd_bus_attach_event(bus_, event, SD_EVENT_PRIORITY_NORMAL);
  if (r < 0) throw bus_error("cannot attach the bus to the event loop", r);
}

int DbusService::on_disconnected(sd_bus_message*, void* userdata, sd_bus_error*) {
  static_cast<DbusService*>(userdata)->handler_.bus_lost();
  return 0;
}

DbusService::~DbusService() {
  if (slot_ != nullptr) sd_bus_slot_unref(slot_);
  if (disconnected_slot_ != nullptr) sd_bus_slot_unref(disconnected_slot_);
  if (bus_ != nullptr) {
    sd_bus_flush(bus_);
    sd_bus_detach_event(bus_);
    sd_bus_flush_close_unref(bus_);
  }
}

void DbusService::update(const Status& status) {
  status_ = status;
  std::vector<const char*> names;
  if (!emitted_once_) {
    emitted_once_ = true;
    emitted_ = status_;
    return;  // nobody has seen a previous value to change from
  }
  names = changed_properties(emitted_, status_);
  if (names.empty()) return;
  names.push_back(nullptr);
  sd_bus_emit_properties_changed_strv(bus_, kObjectPath, kInterface,
                                      const_cast<char**>(names.data()));
  emitted_ = status_;
}

void DbusService::alarm_raised(const char* name) {
  sd_bus_emit_signal(bus_, kObjectPath, kInterface, "AlarmRaised", "s", name);
}

void DbusService::alarm_cleared(const char* name) {
  sd_bus_emit_signal(bus_, kObjectPath, kInterface, "AlarmCleared", "s", name);
}

int DbusService::get_property(sd_bus*, const char*, const char*, const char* property,
                              sd_bus_message* reply, void* userdata, sd_bus_error* error) {
  const Status& s = static_cast<DbusService*>(userdata)->status_;
  const std::string_view p(property);
  if (p == "State") return sd_bus_message_append(reply, "s", s.state.c_str());
  if (p == "Pressure") return sd_bus_message_append(reply, "d", s.pressure_mpa);
  if (p == "PressureSetpoint") return sd_bus_message_append(reply, "d", s.pressure_setpoint_mpa);
  if (p == "DecisionThreshold") return sd_bus_message_append(reply, "d", s.decision_threshold);
  if (p == "Flow") return sd_bus_message_append(reply, "d", s.flow_l_per_min);
  if (p == "TankLevel") return sd_bus_message_append(reply, "d", s.tank_level_pct);
  if (p == "Speed") return sd_bus_message_append(reply, "d", s.speed_m_per_s);
  if (p == "Distance") return sd_bus_message_append(reply, "d", s.distance_m);
  if (p == "NozzleDuty") return append_doubles(reply, s.nozzle_duty_pct);
  if (p == "NozzleHealth") return append_doubles(reply, s.nozzle_flow_ratio);
  if (p == "FlowTrim") return sd_bus_message_append(reply, "d", s.flow_trim_correction);
  if (p == "FlowTrimActive") return sd_bus_message_append(reply, "b", s.flow_trim_active ? 1 : 0);
  if (p == "MeteredOverCalibrated") return sd_bus_message_append(reply, "d", s.calibration_ratio);
  if (p == "Estop")
    return sd_bus_message_append(reply, "(bbd)", s.estop_circuit_closed ? 1 : 0,
                                 s.estop_latched ? 1 : 0, s.estop_reaction_ms);
  if (p == "ZoneDensity") return append_doubles(reply, s.zone_density);
  if (p == "Alarms") return append_strings(reply, s.alarms);
  if (p == "RawInputs") {
    int r = sd_bus_message_open_container(reply, 'a', "(sds)");
    for (const auto& input : s.raw_inputs) {
      if (r >= 0)
        r = sd_bus_message_append(reply, "(sds)", input.name.c_str(), input.value,
                                  input.unit.c_str());
    }
    return r < 0 ? r : sd_bus_message_close_container(reply);
  }
  if (p == "AlarmDetails") {
    int r = sd_bus_message_open_container(reply, 'a', "(ssbs)");
    for (const auto& alarm : s.alarm_details) {
      if (r >= 0) {
        r = sd_bus_message_append(reply, "(ssbs)", alarm.name.c_str(), alarm.severity.c_str(),
                                  alarm.present ? 1 : 0, alarm.remedy.c_str());
      }
    }
    return r < 0 ? r : sd_bus_message_close_container(reply);
  }
  if (p == "VolumeSprayed") return sd_bus_message_append(reply, "d", s.volume_sprayed_l);
  if (p == "AreaCovered") return sd_bus_message_append(reply, "d", s.area_covered_m2);
  if (p == "SavingsPercent") return sd_bus_message_append(reply, "d", s.savings_pct);
  if (p == "ApplicationRate") return sd_bus_message_append(reply, "d", s.application_rate_l_per_ha);
  if (p == "TargetRate") return sd_bus_message_append(reply, "d", s.target_rate_l_per_ha);
  if (p == "FrameRate") return sd_bus_message_append(reply, "d", s.frame_rate_hz);
  if (p == "VisionLatencyMs") return sd_bus_message_append(reply, "d", s.vision_latency_ms);
  if (p == "VisionLatencyP99Ms") return sd_bus_message_append(reply, "d", s.vision_latency_p99_ms);
  if (p == "ControlOverruns") {
    return sd_bus_message_append(reply, "t", static_cast<std::uint64_t>(s.control_overruns));
  }
  if (p == "Mode") return sd_bus_message_append(reply, "s", s.mode.c_str());
  if (p == "SpeedSource") return sd_bus_message_append(reply, "s", s.speed_source.c_str());
  if (p == "GnssFix") return sd_bus_message_append(reply, "s", s.gnss_fix.c_str());
  if (p == "Position") {
    return sd_bus_message_append(reply, "(ddd)", s.latitude_deg, s.longitude_deg, s.altitude_m);
  }
  if (p == "GnssSpeed") return sd_bus_message_append(reply, "d", s.gnss_speed_m_per_s);
  if (p == "Course") return sd_bus_message_append(reply, "d", s.course_deg);
  if (p == "GnssHdop") return sd_bus_message_append(reply, "d", s.gnss_hdop);
  if (p == "GnssSatellites") return sd_bus_message_append(reply, "u", s.gnss_satellites);
  if (p == "YawRate") return sd_bus_message_append(reply, "d", s.yaw_rate_deg_per_s);
  if (p == "WheelCalibration") {
    return sd_bus_message_append(reply, "(tsdtd)", s.wheel_calibration_request,
                                 s.wheel_calibration_state.c_str(), s.wheel_calibration_distance_m,
                                 s.wheel_calibration_pulses, s.wheel_calibration_pulses_per_metre);
  }
  if (p == "GnssTime") return sd_bus_message_append(reply, "s", s.gnss_utc.c_str());
  if (p == "Calibration") {
    return sd_bus_message_append(reply, "(sds)", s.calibration_state.c_str(),
                                 s.calibration_progress, s.calibration_message.c_str());
  }
  if (p == "MeterCalibration") {
    return sd_bus_message_append(reply, "(sddd)", s.meter_source.c_str(), s.meter_pulses_per_litre,
                                 s.meter_configured_pulses_per_litre, s.meter_error_pct);
  }
  if (p == "NozzleCalibration") {
    int r = sd_bus_message_open_container(reply, 'a', "(sddd)");
    for (const auto& line : s.nozzle_lines) {
      if (r >= 0) {
        r = sd_bus_message_append(reply, "(sddd)", line.source.c_str(),
                                  line.slope_l_per_min_per_pct, line.intercept_l_per_min,
                                  line.r_squared);
      }
    }
    return r < 0 ? r : sd_bus_message_close_container(reply);
  }
  return sd_bus_error_setf(error, SD_BUS_ERROR_UNKNOWN_PROPERTY, "no property %s", property);
}

int DbusService::method(sd_bus_message* message, void* userdata, sd_bus_error* error) {
  return handle_method_call(message, static_cast<DbusService*>(userdata)->handler_, error);
}

}  // namespace weedspray::daemon
