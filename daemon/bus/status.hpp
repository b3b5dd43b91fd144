// SPDX-License-Identifier: Apache-2.0
// What the daemon shows over D-Bus: one plain snapshot, assembled by the main loop from the
// real-time threads' published values.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "daemon/sprayer/shared_fix.hpp"

namespace weedspray::daemon {

// One latched alarm as the operator sees it (daemon/supervision/alarm_catalog.hpp).
struct AlarmDetail {
  std::string name;
  std::string severity;  // fault | warning
  bool present = false;  // its condition still holds (false: it only waits to be cleared)
  std::string remedy;
  bool operator==(const AlarmDetail&) const = default;
};

// One input as the hardware gives it (commissioning: sprayctl inputs).
struct RawInput {
  std::string name;  // e.g. "pressure_sensor_current"
  double value = 0;
  std::string unit;  // "mA", "pulses", "0/1" ...
  bool operator==(const RawInput&) const = default;
};

struct Status {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::string state = "Starting";
  double pressure_mpa = 0;
  double pressure_setpoint_mpa = 0;
  double decision_threshold = 0;  // the zone density below which the rate law does not spray
  double flow_l_per_min = 0;
  double tank_level_pct = 0;
  double speed_m_per_s = 0;
  double distance_m = 0;
  std::vector<double> nozzle_duty_pct;
  std::vector<double> zone_density;
  std::vector<std::string> alarms;         // latched alarm names
  std::vector<AlarmDetail> alarm_details;  // the same alarms, with severity and remedy
  double volume_sprayed_l = 0;
  double area_covered_m2 = 0;
  double savings_pct = 0;  // liquid saved against uniform spraying at the nominal dose
  // The metered flow spread over the boom's width at the current speed (L/ha; NaN below
  // kRateMinSpeedMPerS, where it means nothing), and the dose at full weed cover in use
  // (configured, or set live by SetTargetRate).
  static constexpr double kRateMinSpeedMPerS = 0.1;
  double application_rate_l_per_ha = kNaN;
  double target_rate_l_per_ha = 0;
  double frame_rate_hz = 0;
  double vision_latency_ms = 0;      // frame capture -> duty scheduled, latest frame
  double vision_latency_p99_ms = 0;  // over the last 1000 frames
  std::uint64_t control_overruns = 0;
  std::string mode = "hw";             // hw | sim
  std::string speed_source = "wheel";  // wheel | gnss | fixed, "... (gnss fix lost)"
  // GNSS ([gnss] enabled): the latest fix's mode and what it reported; NaN = not given.
  std::string gnss_fix = "off";  // off | none | 2d | 3d
  double latitude_deg = kNaN;
  double longitude_deg = kNaN;
  double altitude_m = kNaN;
  double gnss_speed_m_per_s = kNaN;
  double course_deg = kNaN;
  double gnss_hdop = kNaN;
  std::uint32_t gnss_satellites = 0;
  std::string gnss_utc;  // ISO 8601, "" = unknown
  // Turn compensation's yaw rate, deg/s clockwise (0: off, straight, or too slow for a course).
  double yaw_rate_deg_per_s = 0;
  // The latest wheel calibration (CalibrateWheel): its request number (0: none yet), state
  // (idle, waiting for a straight run, running, done), straight distance and pulses so far, and
  // the result in pulses per metre once done.
  std::uint64_t wheel_calibration_request = 0;
  std::string wheel_calibration_state = "idle";
  double wheel_calibration_distance_m = 0;
  std::uint64_t wheel_calibration_pulses = 0;
  double wheel_calibration_pulses_per_metre = 0;

  // Calibrations from the daemon (daemon/sprayer/calibrations.hpp): the one running or last run
  // (idle, catch_test, awaiting_volume, nozzles, done, cancelled), its progress 0..1 and what
  // it says; the meter's K in use and where from (config | calibration), the configured K and
  // the catch test's error of it (%); each nozzle's line in use and its fit's R^2.
  std::string calibration_state = "idle";
  double calibration_progress = 0;
  std::string calibration_message;
  std::string meter_source = "config";
  double meter_pulses_per_litre = 0;
  double meter_configured_pulses_per_litre = 0;
  double meter_error_pct = 0;
  struct NozzleLineStatus {
    std::string source;  // config | calibration | config (poor fit)
    double slope_l_per_min_per_pct = 0;
    double intercept_l_per_min = 0;
    double r_squared = 0;
    bool operator==(const NozzleLineStatus&) const = default;
  };
  std::vector<NozzleLineStatus> nozzle_lines;
  // [nozzle_health] enabled: each nozzle's flow over its baseline (1 until learned); else empty.
  std::vector<double> nozzle_flow_ratio;
  // The online flow trim: the factor on the modulated nozzles' flows (1 = as calibrated) and
  // whether it is following the meter now (false: held).
  double flow_trim_correction = 1;
  bool flow_trim_active = false;
  // The meter's flow over what the calibrated nozzles promise (a minute's average; 0: not yet
  // known): what calibration_drift judges.
  double calibration_ratio = 0;
  // The emergency stop: whether its circuit is closed (true when none is wired), whether the
  // stop is latched, and the latest trip's time from the edge to valves and pump written safe
  // (ms; 0 before the first trip).
  // Each wired input's raw reading (subsystems not wired are left out).
  std::vector<RawInput> raw_inputs;
  bool estop_circuit_closed = true;
  bool estop_latched = false;
  double estop_reaction_ms = 0;

  bool operator==(const Status&) const = default;
};

// The outcome of a command: empty error_name = done.
struct CommandResult {
  std::string error_name;  // e.g. "org.weedspray.Sprayer1.Error.InvalidArgument"
  std::string message;
  bool ok() const { return error_name.empty(); }
};

inline constexpr const char* kErrorInvalidArgument = "org.weedspray.Sprayer1.Error.InvalidArgument";
inline constexpr const char* kErrorNotPermitted = "org.weedspray.Sprayer1.Error.NotPermitted";
inline constexpr const char* kErrorConfig = "org.weedspray.Sprayer1.Error.Config";
inline constexpr const char* kErrorRateLimited = "org.weedspray.Sprayer1.Error.RateLimited";
inline constexpr const char* kErrorUnavailable = "org.weedspray.Sprayer1.Error.Unavailable";

// The answer to a ReloadConfig call, given once: done, or why the reload was refused.
using ReloadReply = std::function<void(const CommandResult&)>;

// The answer to a Snapshot call, given once: an error, or the PNG's bytes.
using SnapshotReply = std::function<void(const CommandResult&, std::span<const std::uint8_t> png)>;

// Implemented by the daemon; called on the main thread by the D-Bus service.
class CommandHandler {
 public:
  virtual ~CommandHandler() = default;
  virtual CommandResult start() = 0;
  virtual CommandResult stop() = 0;
  virtual CommandResult set_pressure_setpoint(double mpa) = 0;
  // The rate law's decision threshold (spray.decision_threshold's range), and the dose at full
  // weed cover in L/ha (its nozzle flow within spray.nominal_flow_l_per_min's range): both
  // live until the configuration is reloaded, as the set-point is.
  virtual CommandResult set_decision_threshold(double threshold) = 0;
  virtual CommandResult set_target_rate(double l_per_ha) = 0;
  // Re-reads the configuration: the files are parsed and the model probed on a thread of
  // their own, so the main loop goes on meanwhile. A refusal is returned at once (and `reply`
  // never called); once accepted, `reply` is called exactly once, later, from the main thread,
  // when the new configuration is applied or refused.
  virtual CommandResult reload_config(ReloadReply reply) = 0;
  virtual CommandResult clear_alarms() = 0;
  // Simulation only (the soak, tests): a fault by name now (daemon/backends/sim_faults.hpp).
  virtual CommandResult inject_sim_fault(const std::string& name) = 0;
  // The live view: camera `camera`'s next frame with its overlay as a PNG. A refusal is
  // returned at once (and `reply` never called); once accepted, `reply` is called exactly
  // once, later, from the main thread (the frame comes from the camera thread).
  virtual CommandResult snapshot(std::uint32_t camera, SnapshotReply reply) = 0;
  // Wheel calibration from GNSS over a straight run of `run_distance_m`: sets `request` to the
  // number the WheelCalibration property reports it under.
  virtual CommandResult calibrate_wheel(double run_distance_m, std::uint64_t& request) = 0;
  // Meter catch test: every valve open for `seconds` (Idle only); then calibrate_meter with
  // the volume collected. Nozzle sweep: each nozzle alone over calibration.duties_pct. Stop
  // cancels either; the Calibration property follows them.
  virtual CommandResult start_catch_test(double seconds) = 0;
  virtual CommandResult calibrate_meter(double volume_l) = 0;
  virtual CommandResult calibrate_nozzles() = 0;
  // Commissioning (Idle only, run as the calibrations are): nozzle `nozzle` at `duty_pct` for
  // `seconds` with the pump on; the pump alone holding the set-point for `seconds`.
  virtual CommandResult test_valve(std::uint32_t nozzle, double duty_pct, double seconds) = 0;
  virtual CommandResult test_pump(double seconds) = 0;
  // The control loop's latest ground speed (m/s) and odometer (m), and the time of that cycle
  // on this board's clock (ns), with the board's GNSS fix while it is usable (mode none
  // otherwise): what the fleet bridge publishes for boards that share it.
  virtual CommandResult motion(double& speed_m_per_s, double& distance_m, std::uint64_t& time_ns,
                               SharedFix& fix) = 0;
  // speed.source = "fleet": one sample of the owning board's motion, stamped with its clock,
  // and its fix (mode none: none; gnss.source = "fleet" takes it as this board's own).
  virtual CommandResult feed_shared_motion(double speed_m_per_s, double distance_m,
                                           std::uint64_t sender_time_ns, const SharedFix& fix) = 0;
  // The bus connection is gone (the bus daemon stopped or died): nobody can stop the sprayer
  // any more, so it must stop by itself.
  virtual void bus_lost() = 0;
};

}  // namespace weedspray::daemon
