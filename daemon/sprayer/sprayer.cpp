// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/sprayer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <mutex>
#include <opencv2/core.hpp>

#include "control/turn_rate.hpp"
#include "daemon/config/vision_config.hpp"
#include "daemon/sprayer/geometry.hpp"
#include "daemon/sprayer/loop_time.hpp"
#include "daemon/sprayer/step_settings.hpp"

namespace weedspray::daemon {

using loop_time::from_seconds;
using loop_time::seconds;

LiveParams live_params_from(const Config& config) {
  LiveParams p;
  p.setpoint_mpa = config.pressure.setpoint_mpa;
  p.law = spray_law_config(config);
  control::NozzleLine line;
  line.slope_l_per_min_per_pct = config.spray.calibration_slope_l_per_min_per_pct;
  line.intercept_l_per_min = config.spray.calibration_offset_l_per_min;
  line.calibration_pressure_mpa = config.spray.calibration_pressure_mpa;
  p.lines.fill(line);
  p.flow_pulses_per_litre = config.flow.pulses_per_litre;
  p.pressure_compensation = config.spray.pressure_compensation;
  p.over_pressure_mpa = config.alarms.over_pressure_mpa;
  p.stale_timeout_s = config.daemon.input_stale_timeout_s;
  control::validate(p.law);
  control::validate(line);
  return p;
}

Sprayer::Sprayer(const Config& config, Backends& backends)
    : config_(config),
      io_(backends),
      pressure_step_(std::make_unique<control::PressureLoopStep>(pressure_loop_config(config))),
      schedule_(std::make_unique<control::PwmSchedule>(pwm_config(config))),
      nozzle_command_(nozzle_command_config(config)),
      estop_(std::make_unique<EstopGuard>(*backends.clock, backends.estop, backends.valves,
                                          backends.pump)) {
  // pressure.loop_hz goes down to 10 Hz: the watch waits three of the loop's periods, never less
  // than 50 ms (at 20 Hz a fixed 50 ms took the running loop for stalled and stopped the pump).
  pressure_watch_ = io::LoopWatch(std::max(kCrossWatchTimeout, 3 * pressure_period()));
  io::ValvePwmDriverConfig driver;
  driver.command_expiry = from_seconds(config.pwm.dead_man_s);
  // The driver notices a new command only when it wakes: at most 2 ms late (5 mm at 2.5 m/s).
  driver.max_sleep = std::chrono::milliseconds(2);
  driver.miss_tolerance = from_seconds(config.alarms.timing_tolerance_ms / 1e3);
  driver.lateness = &timing_.valve_edges;
  driver.on_wake = [](void* self, Nanos now) noexcept {
    static_cast<Sprayer*>(self)->watch_pressure_loop(now);
  };
  driver.on_wake_context = this;
  driver.heartbeat = io_.heartbeat;
  driver.hold_safe = &estop_->held();
  driver.hold_closed = &valves_held_by_pressure_;
  driver.heartbeat_half_period = from_seconds(0.5 / config.gpio.heartbeat_hz);
  pwm_driver_ = std::make_unique<io::ValvePwmDriver<control::PwmSchedule>>(*io_.clock, *io_.valves,
                                                                           *schedule_, driver);
  io::AnalogIoTiming analog_timing;
  analog_timing.period = pressure_period();
  analog_timing.dac_failures_tolerated =
      static_cast<std::uint32_t>(config.dac.write_failures_tolerated);
  analog_io_ = std::make_unique<io::AnalogIoWorker>(*io_.pressure_adc, *io_.return_valve,
                                                    *io_.clock, analog_timing);
  speed_source_ = parse_speed_source(config.speed.source).value_or(SpeedSource::kWheel);
  if (io_.wheel != nullptr) {
    control::OdometryConfig odometry;
    odometry.pulses_per_metre = config.wheel.pulses_per_metre;
    odometry_.emplace(odometry);
  }
  const auto nozzles = static_cast<std::size_t>(config.boom.nozzles);
  if (config.nozzle_health.enabled) {
    control::NozzleHealthConfig health;
    health.nozzles = nozzles;
    health.baseline_s = config.nozzle_health.baseline_s;
    health.time_constant_s = config.nozzle_health.time_constant_s;
    health.alarm_fraction = config.nozzle_health.alarm_fraction;
    health.judge = config.nozzle_health.judge == "cusum" ? control::NozzleJudge::kCusum
                                                         : control::NozzleJudge::kBand;
    health.alarm_hold_s = config.nozzle_health.alarm_hold_s;
    health.alarm_threshold = config.nozzle_health.alarm_threshold;
    nozzle_health_.emplace(health);
  }
  if (config.nozzle_health.recheck && io_.flow != nullptr) {
    control::NozzleRecheckConfig recheck;
    recheck.nozzles = nozzles;
    recheck.settle_s = config.nozzle_health.recheck_settle_s;
    recheck.measure_s = config.nozzle_health.recheck_measure_s;
    recheck.interval_s = config.nozzle_health.recheck_interval_s;
    recheck.warn_fraction = config.nozzle_health.recheck_warn_pct / 100.0;
    recheck.alarm_fraction = config.nozzle_health.recheck_alarm_pct / 100.0;
    recheck_.emplace(recheck);
  }
  if (config.cameras.size() > kMaxCameras || config.cameras.size() != io_.cameras.size()) {
    throw std::invalid_argument("camera count: at most 8, one backend per [[camera]]");
  }
  nozzle_owner_.assign(nozzles, -1);
  camera_count_ = config.cameras.size();
  // A configuration built in code (tests) has not been through the loader's model check.
  const std::shared_ptr<const LoadedModel> model =
      config.model ? config.model : check_weed_source(config);
  // The camera workers' OpenCV calls (the weed model above all) run on their own thread only:
  // OpenCV's worker pool would take the cores the real-time loops need.
  static std::once_flag single_threaded_opencv;
  std::call_once(single_threaded_opencv, [] { cv::setNumThreads(1); });
  for (std::size_t i = 0; i < camera_count_; ++i) {
    const auto& c = config.cameras[i];
    auto& worker = cameras_[i];
    worker.camera = io_.cameras[i];
    worker.first_nozzle = c.first_nozzle;
    worker.nozzle_count = c.nozzle_count;
    vision::PipelineConfig vision = pipeline_config(config, c, model.get());
    if (!io_.frames_at_camera_scale) vision.frame_mm_per_px = 0.0;
    worker.uses_model = vision::needs_model(vision.weed_source);
    worker.pipeline = std::make_unique<vision::Pipeline>(
        vision,
        model ? std::span<const std::uint8_t>(model->onnx) : std::span<const std::uint8_t>{});
    control::NozzleSchedulerConfig scheduler;
    scheduler.geometry = camera_geometry(c);
    scheduler.nozzles = static_cast<std::size_t>(c.nozzle_count);
    scheduler.rows = static_cast<std::size_t>(config.vision.grid_rows);
    scheduler.opening_delay_s = config.boom.valve_open_delay_s;
    scheduler.closing_delay_s = config.boom.valve_close_delay_s;
    scheduler.gap_policy = control::GapPolicy::kClose;
    worker.scheduler = std::make_unique<control::NozzleScheduler>(scheduler);
    worker.crop_scheduler = std::make_unique<control::NozzleScheduler>(scheduler);
    const auto footprint = control::ground_footprint(scheduler.geometry);
    worker.footprint_length_m = footprint.far_m - footprint.near_m;
    for (int n = c.first_nozzle; n < c.first_nozzle + c.nozzle_count; ++n) {
      nozzle_owner_[static_cast<std::size_t>(n)] = static_cast<int>(i);
    }
  }
  params_.publish(live_params_from(config));
}

Sprayer::~Sprayer() {
  stop();
}

control::GroundInterval Sprayer::footprint(std::size_t i) const noexcept {
  return control::ground_footprint(cameras_[i].scheduler->config().geometry);
}

std::string Sprayer::vision_failures() const {
  std::string failures;
  for (std::size_t i = 0; i < camera_count_; ++i) {
    const CameraStatus status = cameras_[i].status.read();
    if (!status.vision_failed) continue;
    failures += (failures.empty() ? "camera " : "; camera ") + std::to_string(i) + ": " +
                std::string(status.vision_error.data());
  }
  return failures;
}

void Sprayer::feed_shared_motion(double speed_m_per_s, double distance_m,
                                 std::uint64_t sender_time_ns, const SharedFix& fix) noexcept {
  shared_motion_.publish(
      {speed_m_per_s, distance_m, sender_time_ns, io_.clock->now(), ++shared_motion_count_, fix});
}

void Sprayer::start() {
  stopped_ = false;
  safe_write_errors_ = io_.force_safe();  // outputs start safe, explicitly
  // Before any loop runs: a circuit open at start-up holds the outputs from the first cycle.
  if (io_.estop != nullptr) io_.estop->arm(estop_->reaction());
  const auto add = [this](io::ThreadRole role, std::string name, auto body) {
    threads_.emplace_back(role, std::move(body));
    thread_names_.push_back(std::move(name));
  };
  add(io::ThreadRole::kValvePwm, "valve PWM", [this](std::stop_token st) { pwm_driver_->run(st); });
  // The converters' worker reads ahead of the pressure loop's deadlines: both start one
  // period from now so the first sample can be waiting.
  const Nanos first_pressure_deadline = io_.clock->now() + pressure_period();
  add(io::ThreadRole::kAnalogIo, "analog I/O", [this, first_pressure_deadline](std::stop_token st) {
    analog_io_->run(st, first_pressure_deadline);
  });
  add(io::ThreadRole::kPressureLoop, "pressure loop",
      [this, first_pressure_deadline](std::stop_token st) {
        pressure_loop(st, first_pressure_deadline);
      });
  add(io::ThreadRole::kControl, "control loop", [this](std::stop_token st) { control_loop(st); });
  for (std::size_t i = 0; i < camera_count_; ++i) {
    add(io::ThreadRole::kCamera, "camera " + std::to_string(i),
        [this, i](std::stop_token st) { camera_loop(st, cameras_[i]); });
  }
  if (io_.tank != nullptr) {
    add(io::ThreadRole::kModbus, "tank level", [this](std::stop_token st) { tank_loop(st); });
  }
  if (io_.gnss != nullptr) {
    add(io::ThreadRole::kGnss, "gnss", [this](std::stop_token st) { gnss_loop(st); });
  }
  if (io_.yaw_sensor != nullptr) {
    add(io::ThreadRole::kImu, "imu", [this](std::stop_token st) { imu_loop(st); });
  }
}

std::vector<std::string> Sprayer::realtime_warnings() const {
  std::vector<std::string> warnings;
  for (std::size_t i = 0; i < threads_.size(); ++i) {
    const auto status = threads_[i].status();
    if (status == io::RtStatus::kNoPermission || status == io::RtStatus::kFailed) {
      warnings.push_back(thread_names_[i] + ": " + std::string(io::to_string(status)));
    }
  }
  return warnings;
}

void Sprayer::stop() noexcept {
  if (stopped_.exchange(true)) return;
  for (auto& thread : threads_) thread.request_stop();
  for (auto& thread : threads_) thread.stop_and_join();
  threads_.clear();
  if (io_.estop != nullptr) io_.estop->disarm();
  for (std::size_t i = 0; i < camera_count_; ++i) cameras_[i].camera->stop();
  safe_write_errors_ = io_.force_safe();
}

OutputWriteCounters Sprayer::output_write_counters() const noexcept {
  OutputWriteCounters counters;
  const io::ValvePwmStats valves = pwm_driver_->stats();
  const auto at = [](OutputRole role) { return static_cast<std::size_t>(role); };
  const PressureStatus pressure = pressure_.read();
  counters.failed_writes[at(OutputRole::kValves)] =
      valves.write_errors + pressure.valve_safe_write_errors;
  counters.failed_writes[at(OutputRole::kHeartbeat)] = valves.heartbeat_write_errors;
  counters.failed_writes[at(OutputRole::kPump)] = pressure.pump_write_errors;
  const io::AnalogIoStats analog = analog_io_->stats();
  counters.failed_writes[at(OutputRole::kReturnValve)] = analog.dac_faults;
  counters.tolerated_failures[at(OutputRole::kReturnValve)] = analog.dac_tolerated;
  return counters;
}

}  // namespace weedspray::daemon
