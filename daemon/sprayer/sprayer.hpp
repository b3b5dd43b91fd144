// SPDX-License-Identifier: Apache-2.0
// The running sprayer: the real-time loops and workers, wired to the backends.
//   ws-valve-pwm  io::ValvePwmDriver executing control::PwmSchedule edges (highest priority)
//   ws-analog     io::AnalogIoWorker: the pressure ADC reads and return-valve DAC writes
//   ws-pressure   ADC sample -> fuzzy PID / PID -> DAC command, pump relay, over-pressure trip
//   ws-control    wheel odometry, flow, frames -> NozzleScheduler -> spray-rate law -> duties
//   ws-camera     one per camera: frame -> vision::Pipeline -> zone densities (normal
//                 priority; weed-model inferences one at a time through a ticket gate)
//   ws-modbus     tank level
//   ws-gnss       the gpsd client: each GNSS fix into a LatestValue (when [gnss] is enabled)
// Threads exchange trivially copyable values through LatestValue slots and SPSC queues; the
// loops allocate nothing, lock nothing and log nothing after start().
#pragma once

#include <atomic>
#include <memory>
#include <optional>
#include <vector>

#include "control/flow_feedback.hpp"
#include "control/nozzle_command_step.hpp"
#include "control/nozzle_health.hpp"
#include "control/nozzle_recheck.hpp"
#include "control/nozzle_scheduler.hpp"
#include "control/odometry.hpp"
#include "control/phase_windows.hpp"
#include "control/pressure_loop_step.hpp"
#include "control/pwm_schedule.hpp"
#include "control/spray_rate_law.hpp"
#include "control/wheel_calibration.hpp"
#include "daemon/backends/backends.hpp"
#include "daemon/config/config.hpp"
#include "daemon/sprayer/estop_guard.hpp"
#include "daemon/sprayer/ground_speed.hpp"
#include "daemon/sprayer/inference_gate.hpp"
#include "daemon/sprayer/runtime_types.hpp"
#include "daemon/sprayer/shared_motion.hpp"
#include "daemon/sprayer/snapshot_handoff.hpp"
#include "daemon/supervision/loop_timing.hpp"
#include "io/analog_io_worker.hpp"
#include "io/latest_value.hpp"
#include "io/loop_watch.hpp"
#include "io/realtime.hpp"
#include "io/spsc_queue.hpp"
#include "io/tank_level.hpp"
#include "io/valve_pwm_driver.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::daemon {

// Build the parameters the loops re-read live from a configuration.
LiveParams live_params_from(const Config& config);

class Sprayer {
 public:
  static constexpr std::size_t kMaxCameras = daemon::kMaxCameras;
  using FrameQueue = io::SpscQueue<FrameDensities, 16>;
  using LatencyQueue = io::SpscQueue<float, 1024>;
  using RecordQueue = io::SpscQueue<AppliedRecord, 256>;

  // Builds every algorithm object (throws std::invalid_argument naming a bad value).
  Sprayer(const Config& config, Backends& backends);
  ~Sprayer();
  Sprayer(const Sprayer&) = delete;
  Sprayer& operator=(const Sprayer&) = delete;

  void start();
  // Stops and joins every thread, then forces every output safe. Idempotent.
  void stop() noexcept;

  void set_params(const LiveParams& params) noexcept { params_.publish(params); }
  LiveParams params() const noexcept { return params_.read(); }

  PressureStatus pressure() const noexcept { return pressure_.read(); }
  ControlStatus control() const noexcept { return control_.read(); }
  CameraStatus camera(std::size_t i) const noexcept { return cameras_[i].status.read(); }
  std::size_t camera_count() const noexcept { return camera_count_; }
  io::TankLevelSample tank() const noexcept { return tank_.read(); }
  // The latest GNSS fix (mode none and sample_time 0 until the first) and the gpsd link.
  GnssSample gnss() const noexcept { return gnss_.read(); }
  io::GnssLinkStats gnss_link() const noexcept { return gnss_link_.read(); }
  // speed.source = "fleet": one sample of the owning board's speed (m/s), odometer (m) and
  // clock (ns), with its GNSS fix when it has one, stamped with this board's clock now. One
  // caller at a time (the main thread's FeedSharedMotion); the control loop takes the latest.
  void feed_shared_motion(double speed_m_per_s, double distance_m, std::uint64_t sender_time_ns,
                          const SharedFix& fix = {}) noexcept;
  SharedMotionSample shared_motion() const noexcept { return shared_motion_.read(); }
  // Wheel calibration from GNSS (control/wheel_calibration.hpp), run by the gpsd thread on
  // each fix with the wheel counter read as the fix arrives. Starting forgets an earlier
  // result.
  // Returns the request's number (its report carries it), 0 when there is no receiver or no
  // wheel sensor to calibrate.
  std::uint64_t start_wheel_calibration(double run_distance_m) noexcept;
  WheelCalibrationReport wheel_calibration() const noexcept { return wheel_calibration_.read(); }
  io::ValvePwmStats pwm() const noexcept { return pwm_driver_->stats(); }
  // The heartbeat output (the external relay that powers valves and pump) held low from the
  // valve thread's next wake, or beating again (io/valve_pwm_driver.hpp). A refused pump write
  // in the pressure loop stops it too.
  void stop_heartbeat() noexcept { pwm_driver_->stop_heartbeat(); }
  void resume_heartbeat() noexcept { pwm_driver_->resume_heartbeat(); }
  io::AnalogIoStats analog_io() const noexcept { return analog_io_->stats(); }
  // Failed output writes of the real-time threads (unsafe_error left 0).
  OutputWriteCounters output_write_counters() const noexcept;
  // -errno per output of the safe writes of the last start()/stop() (0: written).
  const SafeWriteErrors& safe_write_errors() const noexcept { return safe_write_errors_; }
  // Lateness histograms of the real-time loops (readable from any thread).
  const LoopTiming& timing() const noexcept { return timing_; }
  // Times the valve thread found the pressure loop stalled with the pump on and switched it off.
  std::uint64_t pressure_loop_stalls() const noexcept { return pressure_loop_stalls_.load(); }
  // The emergency stop (daemon/sprayer/estop_guard.hpp): its state and reaction times, and
  // ClearAlarms' unlatching (false while the circuit is open).
  EstopStatus estop() const noexcept { return estop_->status(); }
  bool reset_estop() noexcept { return estop_->reset(); }
  // Threads that asked for SCHED_FIFO but did not get it.
  std::vector<std::string> realtime_warnings() const;

  LatencyQueue& latencies() noexcept { return latencies_; }
  RecordQueue& records() noexcept { return records_; }

  // Ground geometry of camera i (footprint relative to its nadir, for alarms and tests).
  control::GroundInterval footprint(std::size_t i) const noexcept;
  // Cameras whose weed model failed on their latest frame, with why ("camera 1: ..."; empty
  // when none): the vision_model_failed alarm. Their nozzles are held closed meanwhile.
  std::string vision_failures() const;
  // Camera i's live-view handoff (the main thread asks, the camera thread fills).
  SnapshotHandoff& snapshot(std::size_t i) noexcept { return cameras_[i].snapshot; }
  // Tests of the failure handling: while set, camera i's frames count as failed in its weed
  // model (as a network failing at run time makes Pipeline::process() report them).
  void inject_vision_failure(std::size_t i, bool fail) noexcept {
    cameras_[i].injected_failure.store(fail);
  }

 private:
  struct CameraWorker {
    io::Camera* camera = nullptr;
    std::unique_ptr<vision::Pipeline> pipeline;
    std::unique_ptr<control::NozzleScheduler> scheduler;  // owned by the control loop
    // The crop shares, pinned to the ground alike (status and the as-applied record only).
    std::unique_ptr<control::NozzleScheduler> crop_scheduler;
    FrameQueue frames;
    io::LatestValue<CameraStatus> status;
    int first_nozzle = 0;
    int nozzle_count = 0;
    double footprint_length_m = 0;
    double last_frame_distance_m = -1e9;
    bool uses_model = false;     // dnn/hybrid: inference goes through inference_gate_
    bool vision_failed = false;  // control loop: the latest frame failed, nozzles held closed
    std::atomic<bool> injected_failure{false};  // inject_vision_failure()
    SnapshotHandoff snapshot;
  };

  Nanos pressure_period() const noexcept;
  // Runs on the valve thread at every wake: the pressure loop's dead-man.
  void watch_pressure_loop(Nanos now) noexcept;
  void hold_valves_for_pressure(bool fault, PressureStatus& status) noexcept;
  void pressure_loop(std::stop_token stop, Nanos first_deadline) noexcept;
  void control_loop(std::stop_token stop) noexcept;
  void feed_nozzle_health(control::PhaseWindows& windows, Nanos now, bool spraying,
                          std::uint64_t pulses, double pulses_per_litre) noexcept;
  // When the boom last became clear for a re-check (nothing to spray; no crop or stopped).
  struct RecheckWindow {
    Nanos clear_since{-1};
  };
  // One control cycle of the headland re-check (daemon/sprayer/recheck.cpp): whether it holds
  // the valves now; each nozzle's line rescaled by its reading into `scaled_lines`.
  bool step_recheck(RecheckWindow& window, Nanos now, bool spray,
                    std::span<const double> target_flow, const PressureStatus& pressure,
                    const LiveParams& params, ControlStatus& status,
                    std::array<control::NozzleLine, io::kMaxValves>& scaled_lines) noexcept;
  void camera_loop(std::stop_token stop, CameraWorker& worker) noexcept;
  void tank_loop(std::stop_token stop) noexcept;
  void imu_loop(std::stop_token stop) noexcept;
  void gnss_loop(std::stop_token stop) noexcept;

  const Config config_;
  Backends& io_;
  SafeWriteErrors safe_write_errors_{};
  io::LatestValue<LiveParams> params_;
  io::LatestValue<PressureStatus> pressure_;
  io::LatestValue<ControlStatus> control_;
  io::LatestValue<io::TankLevelSample> tank_;
  io::LatestValue<GnssSample> gnss_;  // its one writer: the gpsd thread, or the control loop's
                                      // shared fix (gnss.source = "fleet")
  io::LatestValue<io::GnssLinkStats> gnss_link_;
  io::LatestValue<WheelCalibrationReport> wheel_calibration_;
  io::LatestValue<io::Stamped<double>> imu_yaw_rate_;  // deg/s clockwise, from imu_loop
  io::LatestValue<SharedMotionSample> shared_motion_;  // feed_shared_motion() -> control loop
  std::uint64_t shared_motion_count_ = 0;              // feed_shared_motion()'s caller only
  // start_wheel_calibration(): the run distance (as bits of a double) and a request counter
  // the gpsd thread compares with the last one it served.
  std::atomic<std::uint64_t> wheel_calibration_distance_bits_{0};
  std::atomic<std::uint64_t> wheel_calibration_requests_{0};
  SpeedSource speed_source_ = SpeedSource::kWheel;
  std::unique_ptr<control::PressureLoopStep> pressure_step_;
  std::unique_ptr<io::AnalogIoWorker> analog_io_;
  std::unique_ptr<control::PwmSchedule> schedule_;
  std::unique_ptr<io::ValvePwmDriver<control::PwmSchedule>> pwm_driver_;
  std::optional<control::Odometry> odometry_;
  // The valve duties of each control cycle (law, quantiser, compensation, flow trim); the trim
  // reads the meter against the lines in 1 s windows (whole PWM periods at whole Hz).
  control::NozzleCommandStep nozzle_command_;
  std::unique_ptr<EstopGuard> estop_;  // its latch is read by the valve and pressure loops
  // [nozzle_health] recheck with the meter wired; control loop.
  std::optional<control::NozzleRecheck> recheck_;
  std::optional<control::NozzleHealth> nozzle_health_;  // [nozzle_health] enabled; control loop
  std::array<CameraWorker, kMaxCameras> cameras_;
  InferenceGate inference_gate_;  // one weed-model inference at a time, in arrival order
  std::size_t camera_count_ = 0;
  std::vector<int> nozzle_owner_;  // camera index per nozzle, -1 = none
  LatencyQueue latencies_;
  RecordQueue records_;
  std::vector<io::RealtimeThread> threads_;
  std::vector<std::string> thread_names_;
  std::atomic<bool> stopped_{true};
  LoopTiming timing_;
  // Cross-watch between the valve thread and the pressure loop (io/loop_watch.hpp).
  static constexpr Nanos kCrossWatchTimeout = std::chrono::milliseconds(50);
  io::LoopWatch pressure_watch_{kCrossWatchTimeout};  // used by the valve thread only
  std::atomic<bool> pump_forced_off_{false};
  // Set by the pressure loop while its reading is a sensor fault or a trip: the valve thread
  // holds the valves closed (io::ValvePwmDriverConfig::hold_closed).
  std::atomic<bool> valves_held_by_pressure_{false};
  std::atomic<std::uint64_t> pressure_loop_stalls_{0};
};

}  // namespace weedspray::daemon
