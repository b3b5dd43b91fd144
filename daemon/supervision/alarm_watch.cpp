// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/alarm_watch.hpp"

#include <algorithm>

#include "daemon/supervision/alarm_details.hpp"

namespace weedspray::daemon {
namespace {

Nanos from_seconds(double s) {
  return std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(s));
}

}  // namespace

void AlarmWatch::start(Nanos start_time, const GnssSection& gnss) {
  start_time_ = start_time;
  gnss_lost_fix_.emplace(start_time, from_seconds(gnss.lost_fix_timeout_s),
                         from_seconds(gnss.first_fix_timeout_s));
}

void AlarmWatch::evaluate(Nanos now, const PressureStatus& pressure, const ControlStatus& control,
                          const AlarmSources& from) {
  const Config& config = from.config;
  Sprayer& sprayer = from.sprayer;
  const bool spraying = from.operation.state() == SprayerState::kSpraying;
  AlarmInputs in;
  in.now = now;
  in.spraying = spraying;
  in.pump_commanded = from.operation.pump_enabled();
  in.open_fraction = control.open_fraction;
  in.pressure_valid = pressure.cycles == 0 || pressure.sensor_ok;
  in.pressure_mpa = pressure.pressure_mpa;
  in.over_pressure_trip = pressure.tripped;
  in.sensor_current_ma = pressure.current_ma;
  in.flow_l_per_min = control.flow_l_per_min;
  // From the control loop's own cycles: a valve open between two ticks still counts.
  if (control.cycles > 0 && control.open_fraction == 0.0)
    in.valves_closed_s =
        std::chrono::duration<double>(control.time - control.valves_last_open).count();
  in.tank_enabled =
      from.backends.tank != nullptr && (config.modbus.enabled || from.world.tank_always_read());
  const io::TankLevelSample tank = sprayer.tank();
  in.tank_valid = tank.ok;
  in.tank_level_pct = tank.level_pct;
  if (tank.ok) tank_last_ok_ = tank.time;
  in.tank_last_ok = std::max(tank_last_ok_, start_time_);
  in.camera_expected = spraying;
  in.last_frame_time = now;
  double lead_m = 1e9;
  for (std::size_t i = 0; i < sprayer.camera_count(); ++i) {
    const CameraStatus camera = sprayer.camera(i);
    const auto footprint = sprayer.footprint(i);
    in.last_frame_time =
        std::min(in.last_frame_time, std::max(camera.last_frame_time, spraying_since_));
    lead_m = std::min(lead_m, footprint.near_m + config.cameras[i].distance_to_nozzles_m);
  }
  in.speed_m_per_s = control.speed_m_per_s;
  in.expected_frame_interval_s = 0;
  if (from.world.frames_per_footprint() && control.speed_m_per_s > 0.05 &&
      sprayer.camera_count() > 0) {
    const auto footprint = sprayer.footprint(0);
    in.expected_frame_interval_s = (footprint.far_m - footprint.near_m) / control.speed_m_per_s;
  }
  in.coverage_gap = control.coverage_gaps != coverage_gaps_seen_;
  coverage_gaps_seen_ = control.coverage_gaps;
  in.vision_latency_s = control.last_latency_ms / 1e3;
  in.lead_distance_m = lead_m;
  from.loops.count_misses(sprayer, now, spraying, pressure, control);
  in.overruns_last_second = from.loops.overruns_last_second();
  std::string vision_failures = sprayer.vision_failures();
  in.vision_model_failed = !vision_failures.empty();
  std::string output_failures =
      from.outputs.check(sprayer, from.backends, from.operation.state() == SprayerState::kFault,
                         config.dac.write_failures_tolerated);
  in.output_write_failed = !output_failures.empty();
  in.exit_watcher_lost = !from.exit_watch.running(now);
  in.gnss_fix_lost = from.backends.has_gnss() && gnss_lost_fix_->lost(sprayer.gnss(), now);
  // Not from a status older than the last ClearAlarms (the detector restarts on it).
  in.nozzle_flow_fault = (control.nozzle_flow_fault >= 0 &&
                          control.nozzle_health_reset == from.operation.trip_reset()) ||
                         control.recheck_alarmed >= 0;
  in.nozzle_off_calibration = control.recheck_warned >= 0;
  in.calibration_ratio = control.calibration_ratio;
  in.estop_latched = sprayer.estop().latched;
  in.records_at_risk = from.records.at_risk();
  in.shared_speed_lost =
      control.cycles > 0 && control.shared_motion_lost && (control.shared_motion_seen || spraying);

  const AlarmMask raised = alarms_.evaluate(in);
  report_alarms_cleared(alarms_.cleared_by_itself(), "its condition ended", from.bus);
  if (raised != 0) {
    std::string timing_line;
    if (raised & alarm_bit(AlarmId::kControlOverruns))
      timing_line = from.loops.report_line(sprayer, from.backends.clock->now(), pressure, control);
    const AlarmMeasurements m{in,
                              pressure,
                              control,
                              config,
                              sprayer,
                              std::move(output_failures),
                              std::move(vision_failures),
                              from.exit_watch.lost_because(),
                              from.backends.wheel != nullptr,
                              from.loops.overruns_last_second(),
                              std::move(timing_line),
                              from.records.log_dir()};
    report_alarms_raised(raised, m, from.bus);
  }
  if (alarms_.fault_latched() && from.operation.state() != SprayerState::kFault) {
    from.operation.transition(StateEvent::kFault, "alarm");
  }
  // A latched Fault stops the heartbeat: the external relay cuts valves and pump whatever the
  // outputs do. ClearAlarms lets it beat again.
  if (alarms_.fault_latched()) sprayer.stop_heartbeat();
  if (from.operation.state() == SprayerState::kSpraying) {
    if (!was_spraying_) spraying_since_ = now;
    was_spraying_ = true;
  } else {
    was_spraying_ = false;
  }
  from.outputs.show_alarms(from.backends, alarms_.active() != 0, alarms_.fault_latched());
}

}  // namespace weedspray::daemon
