// SPDX-License-Identifier: Apache-2.0
// Alarm evaluation as pure logic: inputs (the latest measurements and counters) in, latched
// alarms out. Each alarm stays latched until ClearAlarms; a fault-class alarm puts the sprayer
// in Fault (valves closed, pump off). The caller signals, logs and drives buzzer/LED.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string_view>

#include "daemon/config/config.hpp"

namespace weedspray::daemon {

enum class AlarmId : std::uint8_t {
  kOverPressure,         // pressure above alarms.over_pressure_mpa: pump off
  kPressureSensorFault,  // loop current < 3.6 mA or > 21 mA
  kLineBlocked,          // pressure high and flow low while the pump runs and valves are open
  kNoFlow,               // pump on, valves open, pressure normal, no flow (pump, meter or tank)
  kTankLow,
  kTankEmpty,
  kModbusSilent,          // the tank sensor stopped answering
  kCameraLost,            // no frame for alarms.camera_stall_s
  kVisionTooSlow,         // frames do not cover the ground at this speed, or arrive too late
  kControlOverruns,       // control loops missing their deadlines
  kVisionModelFailed,     // a camera's weed model fails at run time: that camera's nozzles closed
  kOutputWriteFailed,     // a valve/pump/return-valve/alarm output refused a write (line named)
  kGnssFixLost,           // GNSS enabled, no usable fix for gnss.lost_fix_timeout_s
  kNozzleFlowFault,       // one nozzle's flow off its baseline ([nozzle_health]; nozzle named)
  kCalibrationDrift,      // the flow trim has held the boom off its calibration: recalibrate
  kFlowValvesClosed,      // flow with every valve commanded closed: a leaking or stuck-open valve
  kEstop,                 // the emergency-stop circuit opened: outputs held safe until reset
  kRecordsDiskFull,       // as-applied lines not written, or free space under log.min_free_mb
  kExitWatcherLost,       // the process that writes the outputs safe after a kill -9 is gone
  kSharedSpeedLost,       // speed.source = "fleet": the owning board's samples stopped
  kNozzleOffCalibration,  // the headland re-check read a nozzle off its calibration (named)
};
inline constexpr std::size_t kAlarmCount = 21;

using AlarmMask = std::uint32_t;
constexpr AlarmMask alarm_bit(AlarmId id) noexcept {
  return AlarmMask{1} << static_cast<int>(id);
}

std::string_view alarm_name(AlarmId id) noexcept;  // "over_pressure", ...
std::optional<AlarmId> parse_alarm(std::string_view name) noexcept;
// Fault-class alarms latch the Fault state; the others are warnings.
bool is_fault(AlarmId id) noexcept;
// Unlatched by the evaluation that finds its condition gone, not only by ClearAlarms.
bool clears_itself(AlarmId id) noexcept;

struct AlarmInputs {
  std::chrono::nanoseconds now{};
  bool spraying = false;
  bool pump_commanded = false;  // the pump is asked to run: spraying, or a calibration in Idle
  double open_fraction = 0;     // mean commanded valve duty, 0..1
  bool pressure_valid = false;  // false: sensor fault (see sensor_current_ma)
  double pressure_mpa = 0;
  bool over_pressure_trip = false;  // the pressure loop already cut the pump
  double sensor_current_ma = 0;
  double flow_l_per_min = 0;
  double valves_closed_s = 0;  // how long every valve has been commanded closed (0: one is open)
  bool tank_enabled = false;
  bool tank_valid = false;
  double tank_level_pct = 0;
  std::chrono::nanoseconds tank_last_ok{};  // last good tank read (or start time)
  bool camera_expected = false;
  std::chrono::nanoseconds last_frame_time{};  // newest frame of the stalest camera (or start)
  double expected_frame_interval_s = 0;        // frames are due this often (ground pacing)
  double speed_m_per_s = 0;
  bool coverage_gap = false;    // consecutive frames left unseen ground since the last evaluation
  double vision_latency_s = 0;  // frame capture to scheduled
  double lead_distance_m = 0;   // from the near edge of the footprint to the nozzles
  std::uint64_t overruns_last_second = 0;
  bool vision_model_failed = false;  // some camera's latest frame failed in its weed model
  bool output_write_failed = false;  // an output write failed since the last evaluation
  bool exit_watcher_lost = false;    // hardware mode: no exit watcher runs (one could not start)
  bool gnss_fix_lost = false;        // see gnss_fix_lost() (daemon/sprayer/ground_speed.hpp)
  bool nozzle_flow_fault = false;    // the nozzle health detector or the re-check names a nozzle
  // The headland re-check's last reading of some nozzle is off its calibration by
  // nozzle_health.recheck_warn_pct (its next reading within it clears the warning).
  bool nozzle_off_calibration = false;
  // The line meter's flow over what the calibrated nozzles promise at the commanded duties,
  // averaged (control::CalibrationRatio; 1 = as calibrated, and while not yet known).
  double calibration_ratio = 1.0;
  // The emergency stop is latched (daemon/sprayer/estop_guard.hpp): its circuit opened and
  // it has not been reset since.
  bool estop_latched = false;
  bool records_at_risk = false;  // see records_at_risk() (daemon/records/records_space.hpp)
  // speed.source = "fleet": no sample for speed.shared_timeout_s, once one came or spraying.
  bool shared_speed_lost = false;
};

class AlarmEvaluator {
 public:
  explicit AlarmEvaluator(const AlarmsSection& thresholds) : thresholds_(thresholds) {}
  void set_thresholds(const AlarmsSection& thresholds) { thresholds_ = thresholds; }

  // Returns the alarms raised by this call (not already latched).
  AlarmMask evaluate(const AlarmInputs& in);
  // The alarms the last evaluation unlatched because their condition ended (clears_itself).
  AlarmMask cleared_by_itself() const noexcept { return cleared_by_itself_; }
  AlarmMask active() const noexcept { return latched_; }
  bool fault_latched() const noexcept;
  // Unlatches everything; a condition still present is raised again on the next evaluation
  // (after its debounce). Returns the alarms that were latched.
  AlarmMask clear() noexcept;
  // Conditions present in the last evaluation (latched or not).
  AlarmMask present() const noexcept { return present_; }

 private:
  AlarmsSection thresholds_;
  AlarmMask latched_ = 0;
  AlarmMask present_ = 0;
  AlarmMask cleared_by_itself_ = 0;
  std::array<std::optional<std::chrono::nanoseconds>, kAlarmCount> condition_since_{};
};

}  // namespace weedspray::daemon
