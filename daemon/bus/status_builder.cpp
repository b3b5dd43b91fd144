// SPDX-License-Identifier: Apache-2.0
#include "daemon/bus/status_builder.hpp"

#include <algorithm>
#include <chrono>

#include "daemon/bus/raw_inputs.hpp"
#include "daemon/config/target_rate.hpp"
#include "daemon/records/map_geometry.hpp"
#include "daemon/supervision/alarm_catalog.hpp"

namespace weedspray::daemon {
namespace {

// "2026-06-24T14:30:05.000Z" (the as-applied log's format); "" for 0 (unknown).
std::string utc_iso8601(std::int64_t utc_ns) {
  return utc_ns == 0 ? std::string() : format_utc_ms(utc_ns);
}

// The latest fix: its mode ("none" too once older than the lost-fix timeout), and the
// position and motion it reported (NaN: not given).
void add_gnss_status(Status& s, const GnssSample& sample, Nanos now, Nanos timeout) {
  const io::GnssFix& fix = sample.value;
  const bool fresh = now - sample.sample_time <= timeout;
  s.gnss_fix = std::string(io::to_string(fresh ? fix.mode : io::GnssFixMode::kNone));
  s.latitude_deg = fix.latitude_deg;
  s.longitude_deg = fix.longitude_deg;
  s.altitude_m = fix.altitude_m;
  s.gnss_speed_m_per_s = fix.speed_m_per_s;
  s.course_deg = fix.course_deg;
  s.gnss_hdop = fix.hdop;
  s.gnss_satellites = fix.satellites_used;
  s.gnss_utc = utc_iso8601(fix.utc_ns);
}

void add_alarms(Status& s, const AlarmEvaluator& alarms) {
  for (std::size_t i = 0; i < kAlarmCount; ++i) {
    const auto id = static_cast<AlarmId>(i);
    if (!(alarms.active() & alarm_bit(id))) continue;
    s.alarms.emplace_back(alarm_name(id));
    s.alarm_details.push_back({std::string(alarm_name(id)), std::string(alarm_severity(id)),
                               (alarms.present() & alarm_bit(id)) != 0,
                               std::string(alarm_catalog_entry(id).remedy)});
  }
}

}  // namespace

Status build_status(const StatusSources& from, const PressureStatus& pressure,
                    const ControlStatus& control) {
  const Sprayer& sprayer = from.sprayer;
  Status s;
  s.state = std::string(to_string(from.state));
  s.mode = from.backends.mode;
  s.pressure_mpa = pressure.pressure_mpa;
  s.pressure_setpoint_mpa = from.setpoint_mpa;
  s.decision_threshold = from.decision_threshold;
  s.flow_l_per_min = control.flow_l_per_min;
  s.tank_level_pct = sprayer.tank().level_pct;
  s.speed_m_per_s = control.speed_m_per_s;
  s.speed_source = std::string(to_string(control.speed_source));
  s.yaw_rate_deg_per_s = control.yaw_rate_deg_per_s;
  const WheelCalibrationReport calibration = sprayer.wheel_calibration();
  s.wheel_calibration_request = calibration.request;
  s.wheel_calibration_state = std::string(to_string(calibration.status.state));
  s.wheel_calibration_distance_m = calibration.status.distance_m;
  s.wheel_calibration_pulses = calibration.status.pulses;
  s.wheel_calibration_pulses_per_metre = calibration.status.pulses_per_metre;
  if (control.speed_fell_back) {
    s.speed_source +=
        control.speed_source == SpeedSource::kFleet ? " (samples lost)" : " (gnss fix lost)";
  }
  s.distance_m = control.distance_m;
  if (from.backends.has_gnss()) {
    add_gnss_status(s, sprayer.gnss(), from.backends.clock->now(),
                    std::chrono::duration_cast<Nanos>(
                        std::chrono::duration<double>(from.config.gnss.lost_fix_timeout_s)));
  }
  s.nozzle_duty_pct.assign(control.duty_pct.begin(), control.duty_pct.begin() + control.nozzles);
  s.zone_density.assign(control.density.begin(), control.density.begin() + control.nozzles);
  add_alarms(s, from.alarms);
  s.volume_sprayed_l = from.totals.volume_l;
  s.area_covered_m2 = from.totals.area_m2;
  s.savings_pct = from.totals.savings_pct();
  const double boom_width_m = from.config.boom.nozzle_width_m * from.config.boom.nozzles;
  if (control.speed_m_per_s >= Status::kRateMinSpeedMPerS) {
    s.application_rate_l_per_ha =
        rate_for_nozzle_flow(control.flow_l_per_min, boom_width_m, control.speed_m_per_s);
  }
  s.target_rate_l_per_ha =
      rate_for_nozzle_flow(from.nominal_flow_l_per_min, from.config.boom.nozzle_width_m,
                           from.config.spray.nominal_speed_m_per_s);
  for (std::size_t i = 0; i < sprayer.camera_count(); ++i) {
    s.frame_rate_hz += sprayer.camera(i).frame_rate_hz;
  }
  s.vision_latency_ms = control.last_latency_ms;
  s.vision_latency_p99_ms = from.vision_latency_p99_ms;
  s.control_overruns = from.control_overruns;
  if (from.calibrations != nullptr) from.calibrations->fill_status(s);
  if (from.config.nozzle_health.enabled) {
    const std::size_t n = std::min<std::size_t>(control.nozzles, control::kMaxHealthNozzles);
    s.nozzle_flow_ratio.assign(control.nozzle_flow_ratio.begin(),
                               control.nozzle_flow_ratio.begin() + n);
  }
  s.flow_trim_correction = control.flow_trim_correction;
  s.calibration_ratio = control.calibration_ratio_known ? control.calibration_ratio : 0.0;
  s.flow_trim_active = control.flow_trim_active;
  s.raw_inputs = raw_inputs(from.backends, pressure, sprayer.tank());
  const EstopStatus estop = sprayer.estop();
  s.estop_circuit_closed = estop.circuit_closed;
  s.estop_latched = estop.latched;
  s.estop_reaction_ms = std::chrono::duration<double, std::milli>(estop.last_reaction).count();
  return s;
}

}  // namespace weedspray::daemon
