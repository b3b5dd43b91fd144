// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/alarm_details.hpp"

#include <spdlog/fmt/fmt.h>

#include <chrono>
#include <cmath>

#include "control/flow_feedback.hpp"
#include "daemon/logging.hpp"
#include "daemon/supervision/alarm_log.hpp"

namespace weedspray::daemon {
namespace {

std::string estop_detail(const EstopStatus& estop) {
  return fmt::format(
      "valves and pump written safe {:.3f} ms after the edge (largest {:.3f} ms), {} safe "
      "write(s) refused; latched until the circuit is closed and the alarms are cleared",
      std::chrono::duration<double, std::milli>(estop.last_reaction).count(),
      std::chrono::duration<double, std::milli>(estop.max_reaction).count(),
      estop.safe_write_errors);
}

// How long the owning board has been silent, by this board's clock.
std::string shared_speed_detail(const AlarmMeasurements& m) {
  const SharedMotionSample last = m.sprayer.shared_motion();
  const std::string silent =
      last.count == 0
          ? std::string("no sample yet")
          : fmt::format("last sample {:.2f} s ago",
                        std::chrono::duration<double>(m.control.time - last.arrival).count());
  return fmt::format("board {}: {} (speed.shared_timeout_s = {} s); every valve closed",
                     m.config.fleet.speed_from, silent, m.config.speed.shared_timeout_s);
}

// The re-check's nozzle n (-1: none any more) and its reading against its calibration.
std::string recheck_detail(int n, const AlarmMeasurements& m) {
  if (n < 0) return "no nozzle off its calibration any more";
  const double ratio = m.control.recheck_ratio[static_cast<std::size_t>(n)];
  return fmt::format(
      "nozzle {}: {:.3f} ({:+.1f} %) of its calibrated held-open flow at the headland re-check; "
      "its line rescaled",
      n, ratio, (ratio - 1.0) * 100.0);
}

// What the control loop uses without a fix (it switched on its own, at the same timeout).
std::string gnss_detail(const AlarmMeasurements& m) {
  GroundSpeedInputs without_fix;
  without_fix.source = parse_speed_source(m.config.speed.source).value_or(SpeedSource::kWheel);
  without_fix.wheel_wired = m.wheel_wired;
  if (m.config.gnss.source == "fleet") {
    return fmt::format("no usable fix for {} s; board {} shares none (its fix or its samples lost)",
                       m.config.gnss.lost_fix_timeout_s, m.config.fleet.speed_from);
  }
  return fmt::format(
      "no usable fix for {} s; gpsd at {}:{} {}; speed from {}", m.config.gnss.lost_fix_timeout_s,
      m.config.gnss.host, m.config.gnss.port,
      m.sprayer.gnss_link().connected ? "connected: the receiver has no fix" : "not reachable",
      to_string(select_ground_speed(without_fix).used));
}

std::string calibration_drift_detail(const AlarmMeasurements& m) {
  const double ratio = m.control.calibration_ratio;
  const double c = m.control.flow_trim_correction;
  const control::FlowTrimConfig trim;
  return fmt::format(
      "the line meter has read {:.1f} % {} than the calibrated nozzles promise at the "
      "commanded duties for {} s; the flow trim at x{:.3f}{}",
      std::abs(ratio - 1.0) * 100.0, ratio > 1.0 ? "more" : "less",
      m.config.alarms.calibration_drift_hold_s, c,
      c <= trim.min_correction || c >= trim.max_correction
          ? " is at its limit: the dose is NOT held"
          : " corrects the modulated nozzles by the boom's common change");
}

}  // namespace

std::string alarm_detail(AlarmId id, const AlarmMeasurements& m) {
  switch (id) {
    case AlarmId::kOutputWriteFailed:
      return m.output_failures + "; every other output driven safe";
    case AlarmId::kFlowValvesClosed:
      return fmt::format(
          "{:.3f} L/min through the meter with every valve commanded closed for {:.1f} s",
          m.in.flow_l_per_min, m.in.valves_closed_s);
    case AlarmId::kPressureSensorFault:
      return fmt::format("loop current {:.2f} mA", m.pressure.current_ma);
    case AlarmId::kOverPressure:
      return fmt::format("{:.3f} MPa, trip at {:.3f} MPa", m.pressure.pressure_mpa,
                         m.config.alarms.over_pressure_mpa);
    case AlarmId::kEstop:
      return estop_detail(m.sprayer.estop());
    case AlarmId::kControlOverruns:
      return fmt::format("{} deadline misses while spraying in the last second; {}",
                         m.overruns_last_second, m.timing_line);
    case AlarmId::kGnssFixLost:
      return gnss_detail(m);
    case AlarmId::kNozzleFlowFault: {
      if (m.control.recheck_alarmed >= 0) return recheck_detail(m.control.recheck_alarmed, m);
      const int n = m.control.nozzle_flow_fault;
      const double ratio = n >= 0 ? m.control.nozzle_flow_ratio[static_cast<std::size_t>(n)] : 1.0;
      return fmt::format("nozzle {}: {}, its flow {:.2f} of its baseline", n,
                         m.control.nozzle_flow_fault_low ? "blocked" : "over (worn or stuck open)",
                         ratio);
    }
    case AlarmId::kNozzleOffCalibration:
      return recheck_detail(m.control.recheck_warned, m);
    case AlarmId::kCalibrationDrift:
      return calibration_drift_detail(m);
    case AlarmId::kRecordsDiskFull:
      return fmt::format("log.min_free_mb = {} MB in {}", m.config.log.min_free_mb,
                         m.records_dir.string());
    case AlarmId::kVisionModelFailed:
      return m.vision_failures;
    case AlarmId::kExitWatcherLost:
      return m.exit_watcher_lost;
    case AlarmId::kSharedSpeedLost:
      return shared_speed_detail(m);
    case AlarmId::kTankLow:
    case AlarmId::kTankEmpty:
      return fmt::format("{:.0f} %", m.in.tank_level_pct);
    default:
      return {};
  }
}

void report_alarms_raised(AlarmMask raised, const AlarmMeasurements& m, DbusService* bus) {
  for (std::size_t i = 0; i < kAlarmCount; ++i) {
    const auto id = static_cast<AlarmId>(i);
    if (!(raised & alarm_bit(id))) continue;
    log_alarm_raised(id, alarm_detail(id, m), logs_to_journal());
    if (bus != nullptr) bus->alarm_raised(std::string(alarm_name(id)).c_str());
  }
}

void report_alarms_cleared(AlarmMask cleared, std::string_view why, DbusService* bus) {
  for (std::size_t i = 0; i < kAlarmCount; ++i) {
    const auto id = static_cast<AlarmId>(i);
    if (!(cleared & alarm_bit(id))) continue;
    log_alarm_cleared(id, why, logs_to_journal());
    if (bus != nullptr) bus->alarm_cleared(std::string(alarm_name(id)).c_str());
  }
}

}  // namespace weedspray::daemon
