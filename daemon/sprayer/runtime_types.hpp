// SPDX-License-Identifier: Apache-2.0
// Values exchanged between the daemon's threads. All trivially copyable: they travel through
// io::LatestValue slots and io::SpscQueue rings, never through locks.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>

#include "control/nozzle_health.hpp"
#include "control/spray_rate_law.hpp"
#include "control/wheel_calibration.hpp"
#include "daemon/sprayer/ground_speed.hpp"
#include "io/gnss.hpp"
#include "io/valve_pwm_driver.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::daemon {

using Nanos = std::chrono::nanoseconds;

// Main thread -> real-time loops, re-read when their version changes.
struct LiveParams {
  double setpoint_mpa = 0;
  bool pump_enabled = false;    // Idle or Spraying
  bool valves_enabled = false;  // Spraying
  // Incremented by ClearAlarms: re-arms the over-pressure trip and restarts nozzle health's
  // baseline (the nozzle was cleaned or changed).
  std::uint64_t trip_reset = 0;
  control::SprayLawConfig law{};
  // Each nozzle's valve line: its own calibration, else the configured [spray] line.
  std::array<control::NozzleLine, io::kMaxValves> lines{};
  // The flow meter's K in use: the catch test's, else flow.pulses_per_litre.
  double flow_pulses_per_litre = 8500.0;
  // A calibration (daemon/sprayer/calibration_run.hpp) holds the valves at these duties while
  // the pump runs, in place of the rate law (no trim); false otherwise.
  bool calibration_valves = false;
  std::array<double, io::kMaxValves> calibration_duty_pct{};
  bool pressure_compensation = true;
  double over_pressure_mpa = 1.0;
  double stale_timeout_s = 0.5;
};

// Pressure loop -> everyone.
struct PressureStatus {
  Nanos time{};  // sample time
  double pressure_mpa = 0;
  double current_ma = 0;
  bool sensor_ok = false;
  double closure = 0;  // controller output, return-valve closure 0..1
  bool pump_on = false;
  bool tripped = false;  // over-pressure trip latched (pump off) until trip_reset
  std::uint64_t cycles = 0;
  std::uint64_t overruns = 0;
  std::uint64_t misses = 0;  // lateness that affects spraying (alarms.timing_tolerance_ms)
  std::uint64_t adc_errors = 0;
  std::uint64_t valve_thread_stalls = 0;  // times the valve thread stopped advancing
  std::uint64_t stale_samples = 0;        // cycles whose newest ADC sample was too old to use
  std::uint64_t pump_write_errors = 0;    // pump relay writes refused (on or off)
  std::uint64_t valve_holds = 0;  // times a sensor fault or trip closed the valves from this loop
  Nanos valves_held_at{};         // clock time just after the latest of those closing writes
  std::uint64_t valve_safe_write_errors = 0;  // of those closing writes, the refused ones
};

// Camera worker -> control loop, one per processed frame.
struct FrameDensities {
  Nanos capture_time{};
  Nanos ready_time{};  // vision done
  int rows = 0;
  int cols = 0;
  std::array<double, vision::kMaxZones> density{};       // weed density: the rate law's input
  std::array<double, vision::kMaxZones> crop_density{};  // share of each zone that is crop
  bool vision_failed = false;  // the weed model failed on this frame: densities are zero
};

// Camera worker -> main thread.
struct CameraStatus {
  Nanos last_frame_time{};
  std::uint64_t frames = 0;
  std::uint64_t errors = 0;
  double frame_rate_hz = 0;
  double vision_ms = 0;  // processing time of the last frame
  bool started = false;
  // Frames captured while the previous one was processed, dropped so latency stays one
  // processing time (a weed model slower than the camera's frame interval).
  std::uint64_t frames_skipped = 0;
  double gate_wait_ms = 0;               // last frame's wait for the shared inference gate
  std::uint64_t vision_failures = 0;     // frames the weed model failed on
  bool vision_failed = false;            // the latest frame failed: this camera's nozzles closed
  std::array<char, 200> vision_error{};  // why it failed (NUL-terminated)
  // The latest frame's size packed and its class map's pixels: what a snapshot needs.
  std::size_t frame_bytes = 0;
  std::size_t class_map_pixels = 0;
};

// Control loop -> main thread.
struct ControlStatus {
  Nanos time{};
  double distance_m = 0;
  double speed_m_per_s = 0;
  double flow_l_per_min = 0;
  std::uint64_t flow_pulses = 0;  // the meter's raw count (calibrations difference it)
  std::uint32_t nozzles = 0;
  std::array<double, io::kMaxValves> duty_pct{};
  std::array<double, io::kMaxValves> density{};       // pinned density under each nozzle now
  std::array<double, io::kMaxValves> crop_density{};  // pinned crop share, likewise
  double volume_l = 0;  // the flow meter's pulses at flow.pulses_per_litre, any state (session)
  double area_m2 = 0;   // ground covered while spraying (session)
  double uniform_volume_l = 0;  // nominal dose x area: what uniform spraying would use
  double last_latency_ms = 0;   // frame capture -> scheduled, latest frame
  std::uint64_t frames_scheduled = 0;
  std::uint64_t coverage_gaps = 0;  // frames whose ground did not reach the previous frame's
  std::uint64_t cycles = 0;
  std::uint64_t overruns = 0;
  std::uint64_t misses = 0;  // lateness that affects spraying (alarms.timing_tolerance_ms)
  double open_fraction = 0;
  Nanos valves_last_open{};   // the last cycle that commanded any valve open (0: none yet)
  bool inputs_stale = false;  // valves held closed because an input is stale
  SpeedSource speed_source = SpeedSource::kFixed;  // where speed_m_per_s came from this cycle
  bool speed_fell_back = false;                    // speed.source = "gnss" without a usable fix
  // speed.source = "fleet": no sample within speed.shared_timeout_s (valves held closed), and
  // whether one ever arrived.
  bool shared_motion_lost = false;
  bool shared_motion_seen = false;
  double yaw_rate_deg_per_s = 0;  // turn compensation's yaw rate, clockwise (0: off or straight)
  // Nozzle health ([nozzle_health] enabled): each nozzle's flow over its baseline (1 until the
  // baseline is learned) and the nozzle named at fault (-1: none), its flow down (blocked) or up.
  std::array<double, control::kMaxHealthNozzles> nozzle_flow_ratio{};
  int nozzle_flow_fault = -1;
  bool nozzle_flow_fault_low = false;
  std::uint64_t nozzle_health_reset = 0;  // the LiveParams::trip_reset the detector restarted at
  // The headland re-check (control/nozzle_recheck.hpp): each nozzle's last held-open reading
  // against its calibration (1 until read), the nozzles past its warning and alarm limits (-1:
  // none), whether it holds the valves now and how many whole-boom re-checks completed.
  std::array<double, io::kMaxValves> recheck_ratio{};
  int recheck_warned = -1;
  int recheck_alarmed = -1;
  bool recheck_holding = false;
  std::uint64_t rechecks = 0;
  // The online flow trim (control/flow_feedback.hpp): the factor on the modulated nozzles'
  // flows, and whether its last window moved it (false: held, e.g. too few valves open).
  double flow_trim_correction = 1.0;
  bool flow_trim_active = false;
  // The meter's flow over what the calibrated lines promise at the commanded duties, averaged
  // (control::CalibrationRatio; 1 until known): calibration_drift's measure.
  double calibration_ratio = 1.0;
  bool calibration_ratio_known = false;
};

// gpsd thread -> main thread: the wheel calibration of request `request` (0: none asked).
struct WheelCalibrationReport {
  std::uint64_t request = 0;
  control::WheelCalibrationStatus status{};
};

// Control loop -> as-applied log writer, one per PWM period.
struct AppliedRecord {
  Nanos time{};
  double distance_m = 0;
  double speed_m_per_s = 0;
  double pressure_mpa = 0;
  double flow_l_per_min = 0;
  double volume_l = 0;  // sprayed since the previous record (the totals' counter): a lost
                        // record is volume missing from the log
  std::uint32_t nozzles = 0;
  std::array<float, io::kMaxValves> duty_pct{};
  std::array<float, io::kMaxValves> density{};       // weed density
  std::array<float, io::kMaxValves> crop_density{};  // share of the ground that is crop
  // Each nozzle's own ground speed (turn compensation: v + yaw rate x lateral offset; equal to
  // speed_m_per_s when driving straight or without compensation) and the flow its duty gives
  // by the calibrated line at the measured pressure (0 when closed): rate = flow / (v_i w).
  std::array<float, io::kMaxValves> nozzle_speed_m_per_s{};
  std::array<float, io::kMaxValves> nozzle_flow_l_per_min{};
  // Where the machine was: the latest GNSS fix (mode kNone: no receiver or no fix yet) and when
  // it arrived on the daemon's clock. The log writer extrapolates it to `time` along its course
  // and speed and places each nozzle's patch from it (daemon/sprayer/geometry.hpp).
  io::GnssFix fix{};
  Nanos fix_time{};
  bool fix_usable = false;        // gnss_fix_usable() at `time`
  double yaw_rate_deg_per_s = 0;  // clockwise positive (the course's rate), as the control used it
};

}  // namespace weedspray::daemon
