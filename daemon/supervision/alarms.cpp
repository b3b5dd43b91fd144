// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/alarms.hpp"

#include <cmath>

namespace weedspray::daemon {
namespace {

constexpr std::array<std::string_view, kAlarmCount> kNames = {
    "over_pressure",
    "pressure_sensor_fault",
    "line_blocked",
    "no_flow",
    "tank_low",
    "tank_empty",
    "modbus_silent",
    "camera_lost",
    "vision_too_slow",
    "control_overruns",
    "vision_model_failed",
    "output_write_failed",
    "gnss_fix_lost",
    "nozzle_flow_fault",
    "calibration_drift",
    "flow_with_valves_closed",
    "estop",
    "records_disk_full",
    "exit_watcher_lost",
    "shared_speed_lost",
    "nozzle_off_calibration",
};

double seconds(std::chrono::nanoseconds t) {
  return std::chrono::duration<double>(t).count();
}

}  // namespace

std::string_view alarm_name(AlarmId id) noexcept {
  return kNames[static_cast<std::size_t>(id)];
}

std::optional<AlarmId> parse_alarm(std::string_view name) noexcept {
  for (std::size_t i = 0; i < kAlarmCount; ++i) {
    if (kNames[i] == name) return static_cast<AlarmId>(i);
  }
  return std::nullopt;
}

bool is_fault(AlarmId id) noexcept {
  switch (id) {
    case AlarmId::kOverPressure:
    case AlarmId::kPressureSensorFault:
    case AlarmId::kLineBlocked:
    case AlarmId::kNoFlow:
    case AlarmId::kTankEmpty:
    case AlarmId::kCameraLost:
    case AlarmId::kOutputWriteFailed:
    case AlarmId::kFlowValvesClosed:
    case AlarmId::kEstop:
    case AlarmId::kExitWatcherLost:
    case AlarmId::kSharedSpeedLost:
      return true;
    default:
      return false;
  }
}

bool clears_itself(AlarmId id) noexcept {
  // The records catch up by themselves once space returns, and a nozzle read within its
  // calibration at the next re-check is fine again: nothing for the user to clear.
  return id == AlarmId::kRecordsDiskFull || id == AlarmId::kNozzleOffCalibration;
}

bool AlarmEvaluator::fault_latched() const noexcept {
  for (std::size_t i = 0; i < kAlarmCount; ++i) {
    const auto id = static_cast<AlarmId>(i);
    if ((latched_ & alarm_bit(id)) && is_fault(id)) return true;
  }
  return false;
}

AlarmMask AlarmEvaluator::clear() noexcept {
  const AlarmMask was = latched_;
  latched_ = 0;
  condition_since_.fill(std::nullopt);
  return was;
}

AlarmMask AlarmEvaluator::evaluate(const AlarmInputs& in) {
  const auto& t = thresholds_;
  std::array<bool, kAlarmCount> condition{};
  std::array<double, kAlarmCount> hold_s{};  // how long a condition must last to raise
  const auto set = [&](AlarmId id, bool present, bool needs_debounce) {
    condition[static_cast<std::size_t>(id)] = present;
    hold_s[static_cast<std::size_t>(id)] = needs_debounce ? t.debounce_s : 0.0;
  };
  // Judged whenever the pump is asked to run with valves open: spraying, and the calibrations
  // (a catch test holds every valve open for minutes).
  const bool valves_open = in.pump_commanded && in.open_fraction > 0.05;
  set(AlarmId::kPressureSensorFault, !in.pressure_valid, false);
  // One bad reading (a glitch on the loop, a lost converter sample) must not latch Fault: the
  // pressure loop already stops the pump in every cycle whose reading is bad, so the machine
  // is safe meanwhile; only a fault that persists is latched.
  hold_s[static_cast<std::size_t>(AlarmId::kPressureSensorFault)] = t.sensor_fault_hold_s;
  set(AlarmId::kOverPressure,
      in.over_pressure_trip || (in.pressure_valid && in.pressure_mpa > t.over_pressure_mpa), false);
  set(AlarmId::kLineBlocked,
      valves_open && in.pressure_valid && in.pressure_mpa > t.blocked_pressure_mpa &&
          in.flow_l_per_min < t.blocked_flow_l_per_min,
      true);
  set(AlarmId::kNoFlow,
      valves_open && in.pressure_valid && in.pressure_mpa <= t.blocked_pressure_mpa &&
          in.flow_l_per_min < t.no_flow_l_per_min,
      true);
  // Liquid through the meter with every valve commanded closed, once the line has drained: a
  // valve that leaks, sticks open or whose wire no longer closes it. In every state: with the
  // pump off the line's pressure can still push liquid out.
  set(AlarmId::kFlowValvesClosed,
      in.valves_closed_s >= t.closed_flow_settle_s && in.flow_l_per_min > t.closed_flow_l_per_min,
      true);
  set(AlarmId::kTankLow, in.tank_enabled && in.tank_valid && in.tank_level_pct < t.tank_low_pct,
      true);
  set(AlarmId::kTankEmpty, in.tank_enabled && in.tank_valid && in.tank_level_pct < t.tank_empty_pct,
      true);
  set(AlarmId::kModbusSilent,
      in.tank_enabled && seconds(in.now - in.tank_last_ok) > t.modbus_silent_s, false);
  set(AlarmId::kCameraLost,
      in.camera_expected && seconds(in.now - in.last_frame_time) >
                                t.camera_stall_s + 2 * in.expected_frame_interval_s,
      false);
  const bool moving = in.spraying && in.speed_m_per_s > 0.1;
  set(AlarmId::kVisionTooSlow,
      moving && (in.coverage_gap || in.vision_latency_s * in.speed_m_per_s > in.lead_distance_m),
      false);
  // A warning, not a fault: only the failing camera's nozzles close (in the control loop).
  set(AlarmId::kVisionModelFailed, in.vision_model_failed, false);
  // A fault: an output that cannot be written may be stuck open; everything else is driven
  // safe, and the failing safe write is retried while in Fault.
  set(AlarmId::kOutputWriteFailed, in.output_write_failed, false);
  // A warning: the speed falls back as configured (wheel pulses, else the fixed speed).
  set(AlarmId::kGnssFixLost, in.gnss_fix_lost, false);  // its timeout is the hold
  // A warning: the nozzle still sprays (too little or too much); the detector has its own hold.
  set(AlarmId::kNozzleFlowFault, in.nozzle_flow_fault, false);
  // A warning: the flow trim keeps the boom's total while it can, but a meter and nozzles that
  // disagree this much have changed since their calibration (or were never calibrated): the
  // user should recalibrate (a new calibration starts the measure afresh). Judged in every
  // state: the average is held, not forgotten, between sprays.
  set(AlarmId::kCalibrationDrift,
      std::abs(in.calibration_ratio - 1.0) * 100.0 > t.calibration_drift_pct, false);
  hold_s[static_cast<std::size_t>(AlarmId::kCalibrationDrift)] = t.calibration_drift_hold_s;
  // A fault at once: the reaction has already written the outputs safe on the input's thread.
  set(AlarmId::kEstop, in.estop_latched, false);
  set(AlarmId::kControlOverruns,
      in.overruns_last_second >= static_cast<std::uint64_t>(t.control_overrun_limit), false);
  // A warning: records are no safety function, spraying goes on while they wait in memory.
  set(AlarmId::kRecordsDiskFull, in.records_at_risk, false);
  // A fault: after a kill -9 only ExecStopPost would close the valves, seconds later.
  set(AlarmId::kExitWatcherLost, in.exit_watcher_lost, false);
  // A fault at once (its timeout is the hold): the control loop has already closed the valves,
  // and spraying on a board that no longer knows where it is must wait for the operator.
  set(AlarmId::kSharedSpeedLost, in.shared_speed_lost, false);
  // A warning: the re-check has already rescaled the nozzle's line, so the rate law asks it for
  // the flow it gives; the user should look at it before it gets worse.
  set(AlarmId::kNozzleOffCalibration, in.nozzle_off_calibration, false);

  AlarmMask raised = 0;
  present_ = 0;
  cleared_by_itself_ = 0;
  for (std::size_t i = 0; i < kAlarmCount; ++i) {
    const auto id = static_cast<AlarmId>(i);
    if (!condition[i]) {
      condition_since_[i].reset();
      if (clears_itself(id) && (latched_ & alarm_bit(id))) {
        latched_ &= ~alarm_bit(id);
        cleared_by_itself_ |= alarm_bit(id);
      }
      continue;
    }
    if (!condition_since_[i]) condition_since_[i] = in.now;
    if (seconds(in.now - *condition_since_[i]) < hold_s[i]) continue;
    present_ |= alarm_bit(id);
    if (!(latched_ & alarm_bit(id))) {
      latched_ |= alarm_bit(id);
      raised |= alarm_bit(id);
    }
  }
  return raised;
}

}  // namespace weedspray::daemon
