#include "daemon/sprayer/sprayer.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include <cstring>
#include <mutex>
#include <opencv2/core.hpp>

#include "control/turn_rate.hpp"
#include "daemon/config/vision_config.hpp"
#include "daemon/sprayer/geometry.hpp"
#include "io/signal_conversion.hpp"

namespace weedspray::daemon {
namespace {

using std::chrono::duration;
using namespace std::chrono_literals;

double seconds(Nanos t) {
  return duration<double>(t).count();
}
Nanos from_seconds(double s) {
  return Nanos(static_cast<std::int64_t>(s * 1e9));
}

control::PwmConfig pwm_config(const Config& config) {
  control::PwmConfig pwm;
  const auto n = static_cast<std::size_t>(config.boom.nozzles);
  pwm.valve_count = n;
  pwm.frequency_hz = config.pwm.frequency_hz;
  pwm.phase_mode = config.pwm.staggered ? control::PwmPhaseMode::kStaggered
                                        : control::PwmPhaseMode::kSynchronous;
  if (config.pwm.order == "outer_first") {
    pwm.order = control::outer_first_order(n);
  } else if (config.pwm.order == "inner_first") {
    pwm.order = control::outer_first_order(n);
    std::reverse(pwm.order.begin(), pwm.order.end());
  } else {
    for (std::size_t i = 0; i < n; ++i) pwm.order.push_back(i);
  }
  pwm.min_on_time = from_seconds(config.pwm.min_on_s);
  pwm.min_off_time = from_seconds(config.pwm.min_off_s);
  // A spray start/stop happens when the ground under the nozzle starts/stops needing it, not at
  // the valve's next period start (up to 50 cm later at 2.5 m/s and 5 Hz).
  pwm.immediate_start_stop = true;
  return pwm;
}

// Same meter K and nozzle lines (what the flow trim's correction is relative to).
bool same_calibration(const LiveParams& a, const LiveParams& b, std::size_t nozzles) noexcept {
  if (a.flow_pulses_per_litre != b.flow_pulses_per_litre) return false;
  for (std::size_t n = 0; n < nozzles; ++n) {
    const control::NozzleLine& x = a.lines[n];
    const control::NozzleLine& y = b.lines[n];
    if (x.slope_l_per_min_per_pct != y.slope_l_per_min_per_pct ||
        x.intercept_l_per_min != y.intercept_l_per_min ||
        x.calibration_pressure_mpa != y.calibration_pressure_mpa ||
        x.full_open_flow_l_per_min != y.full_open_flow_l_per_min)
      return false;
  }
  return true;
}

control::FuzzyPidConfig controller_config(const Config& config) {
  const auto& p = config.pressure;
  control::FuzzyPidConfig c;
  c.base.gains = {p.kp, p.ki, p.kd};
  c.base.output_min = p.output_min;
  c.base.output_max = p.output_max;
  c.base.anti_windup = control::AntiWindup::kBackCalculation;
  c.base.derivative_filter_s = 0.01;
  c.correction_weights = {p.cp, p.ci, p.cd};
  c.error_range = p.range_mpa;
  return c;
}

}  // namespace

LiveParams live_params_from(const Config& config) {
  LiveParams p;
  p.setpoint_mpa = config.pressure.setpoint_mpa;
  p.law.nominal_flow_l_per_min = config.spray.nominal_flow_l_per_min;
  p.law.nozzle_width_m = config.boom.nozzle_width_m;
  p.law.nominal_speed_m_per_s = config.spray.nominal_speed_m_per_s;
  p.law.max_density = config.spray.max_density;
  p.law.decision_threshold = config.spray.decision_threshold;
  p.law.min_duty_pct = config.spray.duty_min_pct;
  p.law.max_duty_pct = config.spray.duty_max_pct;
  p.law.low_duty_policy = config.spray.low_duty_policy == "close"
                              ? control::LowDutyPolicy::kClose
                              : control::LowDutyPolicy::kRaiseToMin;
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
      controller_(std::make_unique<control::PressureController>(
          config.pressure.controller == "pid" ? control::PressureControlMode::kPid
                                              : control::PressureControlMode::kFuzzyPid,
          controller_config(config))),
      schedule_(std::make_unique<control::PwmSchedule>(pwm_config(config))),
      flow_trim_(control::FlowTrimConfig{}),
      calibration_ratio_(control::FlowTrimConfig{}),
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
  if (config.spray.quantiser_levels >= 2) {
    std::vector<double> levels{0.0};
    const int n = config.spray.quantiser_levels;
    for (int i = 0; i < n; ++i) {
      const double level = config.spray.duty_min_pct +
                           (config.spray.duty_max_pct - config.spray.duty_min_pct) * i / (n - 1);
      // duty_min_pct = 0 or duty_max_pct = 100: that level is the closed or open one already.
      if (level > levels.back() && level < 100.0) levels.push_back(level);
    }
    levels.push_back(100.0);
    for (std::size_t i = 0; i < nozzles; ++i) {
      quantisers_.emplace_back(levels, config.spray.hysteresis_pct);
    }
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

void Sprayer::watch_pressure_loop(Nanos now) noexcept {
  PressureStatus pressure;
  if (!pressure_.try_read(pressure)) return;
  const bool stalled = pressure_watch_.stale(pressure.cycles, now);
  if (stalled && pressure.pump_on && !pump_forced_off_.load()) {
    // The pressure loop owns the pump, but it is not running: switch the pump off from here
    // (force_safe is a single ioctl, safe beside a writer stuck in the kernel).
    if (io_.pump != nullptr) io_.pump->force_safe();
    pump_forced_off_.store(true);
    pressure_loop_stalls_.fetch_add(1, std::memory_order_relaxed);
  }
}

Nanos Sprayer::pressure_period() const noexcept {
  return from_seconds(1.0 / config_.pressure.loop_hz);
}

void Sprayer::pressure_loop(std::stop_token stop, Nanos first_deadline) noexcept {
  const Nanos period = pressure_period();
  // Two missed converter reads are tolerated; a third (a hung I2C read, a silent Modbus
  // module) makes the sample stale: sensor fault, pump off, return valve open.
  const Nanos max_sample_age = 3 * period;
  // A miss here is a whole period lost: the controller skipped a sample.
  io::PeriodicLoop loop(*io_.clock, period, first_deadline, &timing_.pressure_loop, period);
  io::AnalogSample sample;  // the newest copy obtained; kept when the slot is busy
  LiveParams params = params_.read();
  std::uint64_t params_version = params_.version();
  std::uint64_t trip_reset_seen = params.trip_reset;
  PressureStatus status;
  bool outputs_safe = false;
  const double dt = seconds(period);
  io::LoopWatch valve_thread(kCrossWatchTimeout);
  bool valves_stalled = false;
  while (!stop.stop_requested()) {
    loop.wait_next();
    // The valve thread switched the pump off while this loop was stalled: the pump state this
    // loop believes in is gone, so decide it afresh.
    if (pump_forced_off_.exchange(false)) {
      status.pump_on = false;
      outputs_safe = false;
    }
    io::ValvePwmStats valves;
    if (pwm_driver_->try_stats(valves)) {
      const bool stalled = valve_thread.stale(valves.wakes, io_.clock->now());
      if (stalled && !valves_stalled) ++status.valve_thread_stalls;
      valves_stalled = stalled;
    }
    if (params_.version() != params_version) {
      params_version = params_.version();
      params_.try_read(params);
    }
    analog_io_->try_latest_sample(sample);
    const bool fresh =
        io::AnalogIoWorker::sample_is_fresh(sample, io_.clock->now(), max_sample_age);
    if (sample.ok && !fresh) ++status.stale_samples;
    const io::PressureReading reading = io::pressure_from_sensor_volts(sample.volts, io_.sensor);
    status.time = sample.time;
    status.current_ma = reading.current_ma;
    status.sensor_ok = fresh && reading.ok();
    status.pressure_mpa = status.sensor_ok ? reading.pressure_mpa : 0.0;
    status.adc_errors = sample.error_count;
    if (params.trip_reset != trip_reset_seen) {
      trip_reset_seen = params.trip_reset;
      status.tripped = false;
    }
    // Over-pressure: pump off in this very cycle; the main loop raises the alarm.
    if (status.sensor_ok && status.pressure_mpa > params.over_pressure_mpa) status.tripped = true;
    // A reading that is no pressure (a cut wire, a stale sample) or a trip closes the valves from
    // this loop in this cycle too, not through the control loop's next command and the valve
    // thread's next edge: the flag first (the valve thread holds them closed from its next
    // wake, and undoes a write that raced it), then the safe write itself.
    hold_valves_for_pressure(!status.sensor_ok || status.tripped, status);

    // A stalled valve thread may hold valves open or shut: no pump, return valve open. A
    // latched emergency stop likewise (its reaction has already switched the pump off).
    const bool estop_held = estop_->held().load();
    if (params.pump_enabled && status.sensor_ok && !status.tripped && !valves_stalled &&
        !estop_held) {
      // A refused write leaves the pump as it was: counted (output_write_failed), and tried
      // again next cycle.
      if (io_.pump != nullptr && !status.pump_on && io_.pump->write(1) != 0) {
        ++status.pump_write_errors;
        pwm_driver_->stop_heartbeat();
      } else {
        status.pump_on = true;
      }
      // An emergency stop that came while the pump was being switched on: its safe write may
      // have landed first. Off again at once; the next cycle takes the safe branch.
      if (estop_->held().load() && io_.pump != nullptr) {
        io_.pump->force_safe();
        status.pump_on = false;
      }
      outputs_safe = false;
      if (!controller_->enabled()) {
        controller_->enable(0.0, params.setpoint_mpa, status.pressure_mpa);
      }
      status.closure = controller_->update(params.setpoint_mpa, status.pressure_mpa, dt);
      analog_io_->command(io::dac_volts_from_valve_opening(1.0 - status.closure, io_.drive));
    } else if (!outputs_safe) {
      // A refused safe write is counted and tried again next cycle (outputs_safe stays false).
      const bool pump_safe = io_.pump == nullptr || io_.pump->force_safe() == 0;
      if (!pump_safe) {
        ++status.pump_write_errors;
        pwm_driver_->stop_heartbeat();  // the pump may still run: the relay cuts it
      }
      analog_io_->command_safe();
      controller_->disable();
      status.pump_on = false;
      status.closure = 0.0;
      outputs_safe = pump_safe;
    }
    status.cycles = loop.cycles();
    status.overruns = loop.overruns();
    status.misses = loop.misses();
    pressure_.publish(status);
  }
  if (io_.pump != nullptr) io_.pump->force_safe();
  analog_io_->command_safe();
}

void Sprayer::hold_valves_for_pressure(bool fault, PressureStatus& status) noexcept {
  if (fault == valves_held_by_pressure_.load(std::memory_order_relaxed)) return;
  valves_held_by_pressure_.store(fault);
  if (!fault) return;
  ++status.valve_holds;
  if (io_.valves != nullptr && io_.valves->force_safe() != 0) {
    ++status.valve_safe_write_errors;
    pwm_driver_->stop_heartbeat();  // a valve may stay open: the relay cuts them
  }
  status.valves_held_at = io_.clock->now();
}

// Nozzle health's share of the control loop: the valves' open times and the meter's pulses
// per phase window (daemon/sprayer/phase_windows.hpp) into the detector.
void Sprayer::feed_nozzle_health(PhaseWindows& windows, Nanos now, bool spraying,
                                 std::uint64_t pulses, double pulses_per_litre) noexcept {
  io::ValvePwmStats pwm;
  if (!pwm_driver_->try_stats(pwm)) return;  // the slot was busy: the next cycle catches up
  if (!spraying || pwm.expired) {
    windows.restart();
    return;
  }
  if (windows.update(pwm.schedule_start, pwm.last_mask, pwm.last_mask_written_at, now, pulses,
                     pulses_per_litre)) {
    nozzle_health_->add_window(windows.open_s(), windows.metered_l(), windows.window_s());
  }
}

void Sprayer::control_loop(std::stop_token stop) noexcept {
  // 500 Hz: a frame waits at most 2 ms to be scheduled, and at 2.5 m/s the vehicle moves
  // 5 mm per cycle.
  constexpr Nanos kPeriod = 2ms;
  constexpr Nanos kFlowWindow = 250ms;
  io::PeriodicLoop loop(*io_.clock, kPeriod, io_.clock->now(), &timing_.control_loop,
                        from_seconds(config_.alarms.timing_tolerance_ms / 1e3));
  const std::size_t nozzles = nozzle_owner_.size();
  const Nanos record_period = from_seconds(1.0 / config_.pwm.frequency_hz);
  LiveParams params = params_.read();
  std::uint64_t params_version = params_.version();
  ControlStatus status;
  status.nozzles = static_cast<std::uint32_t>(nozzles);
  Nanos last = io_.clock->now();
  Nanos next_record = last + record_period;
  double volume_at_last_record = 0;
  std::uint64_t flow_count_start = io_.flow != nullptr ? io_.flow->snapshot().count : 0;
  std::uint64_t volume_count = flow_count_start;
  // The trim judges the pressure through the lab rig's 0.1 s filter: a single noisy read off
  // the set-point must not freeze a whole window.
  constexpr double kTrimPressureFilterS = 0.1;
  double trim_pressure_mpa = -1.0;  // < 0: not yet read
  Nanos flow_window_start = last;
  double fixed_distance = 0;
  std::uint64_t frames_lost = 0;
  GnssSample gnss;
  const Nanos lost_fix_timeout = from_seconds(config_.gnss.lost_fix_timeout_s);
  // Turn compensation (control/turn_rate.hpp): each nozzle's ground speed and the extra
  // distance its arc has run beyond the centre line's, so the rate law and the schedule use
  // the nozzle's own travel on a curve.
  const bool gnss_yaw = config_.turn.yaw_source == "gnss" && io_.gnss != nullptr;
  const bool imu_yaw = config_.turn.yaw_source == "imu" && io_.yaw_sensor != nullptr;
  const bool turn_compensation = config_.turn.compensation && (gnss_yaw || imu_yaw);
  constexpr Nanos kImuStale = 100ms;  // 10 of its samples: an older rate is not used
  io::Stamped<double> imu_sample;
  control::YawRateConfig yaw_config;
  yaw_config.min_speed_m_per_s = config_.turn.min_speed_m_per_s;
  yaw_config.filter_time_constant_s = config_.turn.yaw_filter_s;
  yaw_config.max_fix_gap_s = config_.gnss.lost_fix_timeout_s;
  control::YawRateEstimator yaw_rate(yaw_config);
  Nanos last_fix_time{-1};
  std::array<double, io::kMaxValves> right_offset_m{};
  for (std::size_t n = 0; n < nozzles; ++n)
    right_offset_m[n] = nozzle_right_offset_m(config_.boom, n);
  std::array<double, io::kMaxValves> nozzle_speed{};
  std::array<double, io::kMaxValves> arc_extra_m{};  // nozzle's travel minus the centre line's
  std::array<double, io::kMaxValves> frame_odometer{};
  // One staggered phase (period / nozzles); the meter lags the valves by 30 ms (the lab's
  // blockage experiment, lab/experiments/closed_loop_rig.cpp: the valves' 15-25 ms delays).
  PhaseWindows health_windows(
      from_seconds(1.0 / (config_.pwm.frequency_hz *
                          static_cast<double>(std::max<std::size_t>(nozzles, 1)))),
      30ms);
  std::uint64_t health_reset_seen = params.trip_reset;
  LiveParams trim_calibration = params;  // the meter K and lines the trim learned against
  while (!stop.stop_requested()) {
    loop.wait_next();
    const Nanos now = io_.clock->now();
    const double dt = seconds(now - last);
    last = now;
    if (params_.version() != params_version) {
      params_version = params_.version();
      params_.try_read(params);
      // The trim's correction is relative to the calibration it learned against: a new meter K
      // or nozzle line (sprayctl calibrate) starts it afresh.
      if (!same_calibration(trim_calibration, params, nozzles)) {
        flow_trim_.reset();
        meter_windows_.reset();
        calibration_ratio_.reset();
        trim_calibration = params;
      }
    }
    // Travel: the wheel's pulses are the distance base whenever it is wired; the speed comes
    // from speed.source (daemon/sprayer/ground_speed.hpp).
    GroundSpeedInputs speed_in;
    speed_in.source = speed_source_;
    speed_in.wheel_wired = odometry_.has_value();
    speed_in.fixed_speed_m_per_s = config_.wheel.fixed_speed_m_per_s;
    if (odometry_) {
      const io::PulseSnapshot wheel = io_.wheel->snapshot();
      odometry_->update(wheel.count, wheel.last_edge_time, now);
      status.distance_m = odometry_->distance_m();
      speed_in.wheel_speed_m_per_s = odometry_->speed_m_per_s();
    }
    if (io_.gnss != nullptr) {
      gnss_.try_read(gnss);  // a collision with the writer keeps the previous fix
      speed_in.gnss_usable = gnss_fix_usable(gnss, now, lost_fix_timeout);
      speed_in.gnss_speed_m_per_s = gnss.value.speed_m_per_s;
      if (turn_compensation && gnss_yaw && gnss.sample_time != last_fix_time) {
        last_fix_time = gnss.sample_time;
        // The receiver's own fix times difference best (no USB or gpsd latency jitter).
        const double fix_time_s = gnss.value.utc_ns != 0
                                      ? static_cast<double>(gnss.value.utc_ns) * 1e-9
                                      : seconds(gnss.sample_time);
        if (speed_in.gnss_usable) {
          yaw_rate.add_fix(gnss.value.course_deg, gnss.value.speed_m_per_s, fix_time_s);
        } else {
          yaw_rate.reset();
        }
      }
      if (turn_compensation && gnss_yaw && !speed_in.gnss_usable) yaw_rate.reset();
    }
    const GroundSpeed ground = select_ground_speed(speed_in);
    status.speed_m_per_s = ground.speed_m_per_s;
    status.speed_source = ground.used;
    status.speed_fell_back = ground.fell_back;
    if (!odometry_) {
      fixed_distance += status.speed_m_per_s * dt;
      status.distance_m = fixed_distance;
    }
    status.yaw_rate_deg_per_s = 0.0;
    if (turn_compensation && gnss_yaw) status.yaw_rate_deg_per_s = yaw_rate.rate_deg_per_s();
    if (turn_compensation && imu_yaw && imu_yaw_rate_.try_read(imu_sample) &&
        now - imu_sample.sample_time <= kImuStale) {
      status.yaw_rate_deg_per_s = imu_sample.value;
    }
    for (std::size_t n = 0; n < nozzles; ++n) {
      nozzle_speed[n] = control::nozzle_ground_speed_m_per_s(
          status.speed_m_per_s, status.yaw_rate_deg_per_s, right_offset_m[n]);
      arc_extra_m[n] += (nozzle_speed[n] - status.speed_m_per_s) * dt;
    }
    if (io_.flow != nullptr) {
      const io::PulseSnapshot flow = io_.flow->snapshot();
      // The volume is the meter's pulses themselves, counted in every state: integrating the
      // windowed flow below would lag it and lose part of each start and stop.
      status.volume_l +=
          static_cast<double>(flow.count - volume_count) / params.flow_pulses_per_litre;
      volume_count = flow.count;
      status.flow_pulses = flow.count;
      // Measured flow over a sliding window.
      if (now - flow_window_start >= kFlowWindow) {
        status.flow_l_per_min = static_cast<double>(flow.count - flow_count_start) /
                                params.flow_pulses_per_litre / seconds(now - flow_window_start) *
                                60.0;
        flow_count_start = flow.count;
        flow_window_start = now;
      }
    }
    // New frames: pin their densities to the ground they imaged. Densities (not duties) are
    // pinned so the rate law uses the speed and pressure at the moment the patch is sprayed.
    for (std::size_t c = 0; c < camera_count_; ++c) {
      auto& worker = cameras_[c];
      while (auto frame = worker.frames.try_pop()) {
        const double frame_distance =
            odometry_
                ? odometry_->distance_at(frame->capture_time)
                : status.distance_m - status.speed_m_per_s * seconds(now - frame->capture_time);
        const auto zones = static_cast<std::size_t>(frame->rows * frame->cols);
        // More than 5 % of a footprint of ground between two frames was never seen.
        if (frame_distance - worker.last_frame_distance_m > 1.05 * worker.footprint_length_m &&
            worker.last_frame_distance_m > -1e8) {
          ++status.coverage_gaps;
        }
        worker.last_frame_distance_m = frame_distance;
        worker.vision_failed = frame->vision_failed;
        // Each nozzle's own travel when the frame was taken (the centre line's when driving
        // straight): the plan and the look-ahead are in that nozzle's odometer.
        const auto count = static_cast<std::size_t>(worker.nozzle_count);
        const double since_capture_s = seconds(now - frame->capture_time);
        for (std::size_t local = 0; local < count; ++local) {
          const std::size_t n = local + static_cast<std::size_t>(worker.first_nozzle);
          const double extra = nozzle_speed[n] - status.speed_m_per_s;
          frame_odometer[local] = frame_distance + arc_extra_m[n] - extra * since_capture_s;
        }
        const std::span<const double> odometers(frame_odometer.data(), count);
        worker.scheduler->add_frame(odometers,
                                    std::span<const double>(frame->density.data(), zones));
        worker.crop_scheduler->add_frame(
            odometers, std::span<const double>(frame->crop_density.data(), zones));
        const Nanos scheduled = io_.clock->now();
        status.last_latency_ms = seconds(scheduled - frame->capture_time) * 1e3;
        ++status.frames_scheduled;
        if (!latencies_.try_push(static_cast<float>(status.last_latency_ms))) ++frames_lost;
      }
    }
    PressureStatus pressure;
    const bool have_pressure = pressure_.try_read(pressure);
    const bool pressure_stale = !have_pressure || !pressure.sensor_ok ||
                                seconds(now - pressure.time) > params.stale_timeout_s;
    status.inputs_stale = pressure_stale;
    const bool spray = params.valves_enabled && !pressure_stale;
    // A calibration moves liquid only with the pump on (the daemon runs it for the
    // calibration in Idle) and the pressure sensor fresh.
    const bool calibrating = params.calibration_valves && params.pump_enabled &&
                             !params.valves_enabled && !pressure_stale;
    const double compensation_pressure = params.pressure_compensation ? pressure.pressure_mpa : 0.0;

    io::ValveCommand command;
    command.valve_count = static_cast<std::uint32_t>(nozzles);
    control::FlowTrimTick trim_tick;
    double open_sum = 0;
    for (std::size_t n = 0; n < nozzles; ++n) {
      const int owner = nozzle_owner_[n];
      double density = 0;
      if (owner >= 0) {
        const auto& worker = cameras_[static_cast<std::size_t>(owner)];
        // The plan holds densities: the rate law says which of them open the valve, so ground
        // that needs no spray closes the valve with the closing lead.
        const auto sprays = [&](double planned_density) {
          return control::spray_decision(params.law, params.lines[n], planned_density,
                                         nozzle_speed[n], compensation_pressure)
                     .duty_pct > 0.0;
        };
        const std::size_t local = n - static_cast<std::size_t>(worker.first_nozzle);
        const double nozzle_odometer = status.distance_m + arc_extra_m[n];
        density = worker.scheduler->value_at(local, nozzle_odometer, nozzle_speed[n], sprays);
        status.crop_density[n] =
            worker.crop_scheduler->duty_at(local, nozzle_odometer, nozzle_speed[n]);
      }
      status.density[n] = density;
      // A camera whose weed model fails closes its own nozzles until it processes frames again.
      const bool blind = owner >= 0 && cameras_[static_cast<std::size_t>(owner)].vision_failed;
      double duty = 0;
      if (calibrating) {
        duty = params.calibration_duty_pct[n];
      } else if (spray && !blind) {
        const control::SprayDecision decision = control::spray_decision(
            params.law, params.lines[n], density, nozzle_speed[n], compensation_pressure);
        duty = decision.duty_pct;
        if (!quantisers_.empty()) {
          duty = control::clamp_duty_for_flow_pct(
              params.law, quantisers_[n].quantise(std::clamp(decision.raw_duty_pct, 0.0, 100.0)),
              decision.target_flow_l_per_min);
        }
        if (duty >= 100 && !(params.lines[n].full_open_flow_l_per_min > 0))
          trim_tick.promise_known = false;
      } else if (!quantisers_.empty()) {
        quantisers_[n].reset();
      }
      command.duty_pct[n] = duty;
      open_sum += duty / 100.0;
    }
    status.open_fraction = nozzles > 0 ? open_sum / static_cast<double>(nozzles) : 0.0;
    if (open_sum > 0.0) status.valves_last_open = now;
    if (io_.flow != nullptr && spray) {
      // The lab's rig feeds the same trim through the same windows (closed_loop_rig.cpp), so
      // `weedspray-lab experiment orthogonal` measures this law.
      trim_pressure_mpa = trim_pressure_mpa < 0.0
                              ? pressure.pressure_mpa
                              : trim_pressure_mpa + (1.0 - std::exp(-dt / kTrimPressureFilterS)) *
                                                        (pressure.pressure_mpa - trim_pressure_mpa);
      trim_tick.open_fraction = status.open_fraction;
      trim_tick.pressure_error_fraction =
          params.setpoint_mpa > 0 ? (trim_pressure_mpa - params.setpoint_mpa) / params.setpoint_mpa
                                  : 0.0;
      trim_tick.pulses = status.flow_pulses;
      const double correction = flow_trim_.correction();
      for (std::size_t n = 0; n < nozzles; ++n) {
        // The trim moves duties only inside the calibrated band, never into the closed one.
        const double d = command.duty_pct[n];
        if (d > 0 && d < 100) {
          command.duty_pct[n] = std::clamp(
              control::trimmed_duty_pct(params.lines[n], d, correction, compensation_pressure),
              params.law.min_duty_pct, params.law.max_duty_pct);
        }
        // The meter is read against what the lines promise at the duties commanded.
        trim_tick.promised_l_per_min += control::promised_flow_l_per_min(
            params.lines[n], command.duty_pct[n], compensation_pressure);
      }
      control::FlowTrimInput window;
      if (meter_windows_.tick(dt, trim_tick, params.flow_pulses_per_litre, window)) {
        flow_trim_.update(window);
        calibration_ratio_.update(window);
      }
      status.flow_trim_active = !flow_trim_.frozen();
    } else {
      meter_windows_.reset();
      trim_pressure_mpa = -1.0;
      status.flow_trim_active = false;
    }
    status.flow_trim_correction = flow_trim_.correction();
    status.calibration_ratio = calibration_ratio_.ratio();
    status.calibration_ratio_known = calibration_ratio_.known();
    command.issued_at = now;
    pwm_driver_->command(command);
    for (std::size_t n = 0; n < nozzles; ++n) status.duty_pct[n] = command.duty_pct[n];
    if (nozzle_health_ && io_.flow != nullptr) {
      // ClearAlarms after a clean: the nozzles' flows are learned afresh as the new baseline.
      if (params.trip_reset != health_reset_seen) {
        health_reset_seen = params.trip_reset;
        nozzle_health_->reset();
      }
      status.nozzle_health_reset = health_reset_seen;
      feed_nozzle_health(health_windows, now, spray, status.flow_pulses,
                         params.flow_pulses_per_litre);
      for (std::size_t n = 0; n < std::min(nozzles, control::kMaxHealthNozzles); ++n)
        status.nozzle_flow_ratio[n] = nozzle_health_->ratio(n);
      status.nozzle_flow_fault = nozzle_health_->alarmed_nozzle();
      status.nozzle_flow_fault_low = nozzle_health_->alarmed_low();
    }

    if (spray && status.speed_m_per_s > 0) {
      double nozzle_speed_sum = 0;  // the boom's swept width x speed, each nozzle on its arc
      for (std::size_t n = 0; n < nozzles; ++n) nozzle_speed_sum += nozzle_speed[n];
      const double area = nozzle_speed_sum * dt * config_.boom.nozzle_width_m;
      status.area_m2 += area;
      status.uniform_volume_l += control::nominal_dose_l_per_m2(params.law) * area;
    }
    if (now >= next_record) {
      next_record += record_period;
      if (next_record <= now) next_record = now + record_period;
      AppliedRecord record;
      record.time = now;
      record.distance_m = status.distance_m;
      record.speed_m_per_s = status.speed_m_per_s;
      record.pressure_mpa = pressure.pressure_mpa;
      record.flow_l_per_min = status.flow_l_per_min;
      record.volume_l = status.volume_l - volume_at_last_record;
      volume_at_last_record = status.volume_l;
      record.nozzles = status.nozzles;
      for (std::size_t n = 0; n < nozzles; ++n) {
        record.duty_pct[n] = static_cast<float>(status.duty_pct[n]);
        record.density[n] = static_cast<float>(status.density[n]);
        record.crop_density[n] = static_cast<float>(status.crop_density[n]);
        record.nozzle_speed_m_per_s[n] = static_cast<float>(nozzle_speed[n]);
        record.nozzle_flow_l_per_min[n] = static_cast<float>(control::flow_for_duty_l_per_min(
            params.lines[n], status.duty_pct[n], pressure.pressure_mpa));
      }
      if (io_.gnss != nullptr) {
        record.fix = gnss.value;
        record.fix_time = gnss.sample_time;
        record.fix_usable = speed_in.gnss_usable;
      }
      record.yaw_rate_deg_per_s = status.yaw_rate_deg_per_s;
      records_.try_push(record);  // a full queue drops the record (the writer is stuck)
    }
    status.time = now;
    status.cycles = loop.cycles();
    status.overruns = loop.overruns();
    status.misses = loop.misses();
    control_.publish(status);
  }
}

void Sprayer::camera_loop(std::stop_token stop, CameraWorker& worker) noexcept {
  CameraStatus status;
  while (!stop.stop_requested() && !status.started) {
    status.started = worker.camera->start();
    if (!status.started) {
      ++status.errors;
      worker.status.publish(status);
      io_.clock->sleep_until(io_.clock->now() + 1s);
    }
  }
  Nanos previous_frame{};
  Nanos busy_until{};  // when the previous frame's processing ended
  io::Frame frame;
  while (!stop.stop_requested()) {
    const io::FrameStatus got = worker.camera->next_frame(frame, 100ms);
    if (got == io::FrameStatus::kEnd) break;
    if (got != io::FrameStatus::kOk) {
      if (got == io::FrameStatus::kError) ++status.errors;
      continue;
    }
    // A frame captured while the previous one went through the network is already old: skip it
    // for the next, fresh one, so a model slower than the frame interval costs frames, not
    // latency. Colour-only sources take ~1 ms: a frame they find waiting is one delivered late
    // (the thread was held up), and skipping it would leave its ground unseen.
    if (worker.uses_model && frame.timestamp < busy_until) {
      ++status.frames_skipped;
      worker.status.publish(status);
      continue;
    }
    const Nanos asked = io_.clock->now();
    std::optional<InferenceGate::Turn> turn;
    if (worker.uses_model) turn.emplace(inference_gate_.acquire());
    const Nanos t0 = io_.clock->now();
    const vision::FrameResult& result = worker.pipeline->process(frame.view);
    turn.reset();
    FrameDensities densities;
    densities.capture_time = frame.timestamp;
    densities.ready_time = io_.clock->now();
    busy_until = densities.ready_time;
    densities.rows = result.rows;
    densities.cols = result.cols;
    std::copy(result.zone_density.begin(), result.zone_density.end(), densities.density.begin());
    std::copy(result.crop_density.begin(), result.crop_density.end(),
              densities.crop_density.begin());
    // The weed model failed (an empty error is a malformed frame: zero densities, no alarm).
    const bool injected = worker.injected_failure.load();
    densities.vision_failed =
        injected || (!worker.pipeline->last_frame_ok() && !worker.pipeline->last_error().empty());
    status.vision_failed = densities.vision_failed;
    if (densities.vision_failed) {
      if (injected) {
        densities.density.fill(0.0);
        densities.crop_density.fill(0.0);
      }
      ++status.vision_failures;
      static const std::string kInjected = "failure injected by a test";
      const std::string& error = injected ? kInjected : worker.pipeline->last_error();
      const std::size_t n = std::min(error.size(), status.vision_error.size() - 1);
      std::memcpy(status.vision_error.data(), error.data(), n);
      status.vision_error[n] = '\0';
    }
    worker.frames.try_push(densities);
    if (worker.snapshot.wanted())
      worker.snapshot.fill(frame.view, frame.timestamp, *worker.pipeline, result);
    status.frame_bytes = SnapshotHandoff::packed_bytes(frame.view);
    status.class_map_pixels = worker.pipeline->class_map_pixels();
    ++status.frames;
    status.gate_wait_ms = seconds(t0 - asked) * 1e3;
    status.vision_ms = seconds(densities.ready_time - t0) * 1e3;
    if (previous_frame.count() > 0) {
      const double interval = seconds(frame.timestamp - previous_frame);
      if (interval > 0) {
        status.frame_rate_hz = status.frame_rate_hz == 0
                                   ? 1.0 / interval
                                   : 0.8 * status.frame_rate_hz + 0.2 / interval;
      }
    }
    previous_frame = frame.timestamp;
    status.last_frame_time = frame.timestamp;
    worker.status.publish(status);
  }
}

void Sprayer::tank_loop(std::stop_token stop) noexcept {
  const Nanos period = from_seconds(config_.modbus.poll_period_s);
  Nanos next = io_.clock->now();
  while (!stop.stop_requested()) {
    tank_.publish(io_.tank->read());
    next += period;
    // Sleep in short slices so a stop request is honoured promptly.
    while (!stop.stop_requested() && io_.clock->now() < next) {
      io_.clock->sleep_until(std::min(next, io_.clock->now() + 100ms));
    }
  }
}

void Sprayer::gnss_loop(std::stop_token stop) noexcept {
  // Each wait is short so a stop request is honoured promptly; the receiver reconnects itself.
  constexpr Nanos kWait = 100ms;
  const Nanos lost_fix_timeout = from_seconds(config_.gnss.lost_fix_timeout_s);
  control::WheelCalibration calibration(control::WheelCalibrationConfig{});
  std::uint64_t calibration_requests_served = 0;
  while (!stop.stop_requested()) {
    io::GnssFix fix;
    const bool got = io_.gnss->next_fix(fix, kWait);
    // The wheel counter as the fix arrives: the same latency at both ends of a run cancels.
    const std::uint64_t wheel_count = io_.wheel != nullptr ? io_.wheel->snapshot().count : 0;
    const Nanos arrived = io_.clock->now();
    const io::GnssLinkStats link = io_.gnss->stats();
    if (got) gnss_.publish(GnssSample{fix, arrived, link.connect_failures + link.disconnects});
    gnss_link_.publish(link);
    const std::uint64_t requests = wheel_calibration_requests_.load();
    if (requests != calibration_requests_served) {
      calibration_requests_served = requests;
      control::WheelCalibrationConfig config;
      config.run_distance_m = std::bit_cast<double>(wheel_calibration_distance_bits_.load());
      calibration = control::WheelCalibration(config);
      calibration.start();
      wheel_calibration_.publish({requests, calibration.status()});
    }
    if (got && calibration.status().state != control::WheelCalibrationState::kIdle &&
        calibration.status().state != control::WheelCalibrationState::kDone) {
      const GnssSample sample{fix, arrived, 0};
      control::CalibrationFix c;
      c.usable = gnss_fix_usable(sample, arrived, lost_fix_timeout);
      c.latitude_deg = fix.latitude_deg;
      c.longitude_deg = fix.longitude_deg;
      c.course_deg = fix.course_deg;
      c.speed_m_per_s = fix.speed_m_per_s;
      wheel_calibration_.publish({requests, calibration.add_fix(c, wheel_count)});
    }
  }
}

void Sprayer::imu_loop(std::stop_token stop) noexcept {
  // 100 Hz: a sysfs read of an I2C gyro takes ~0.3 ms; the control loop uses the latest.
  constexpr Nanos kPeriod = 10ms;
  io::PeriodicLoop loop(*io_.clock, kPeriod, io_.clock->now());
  std::uint64_t errors = 0;
  while (!stop.stop_requested()) {
    loop.wait_next();
    const io::YawRateSample sample = io_.yaw_sensor->read();
    if (!sample.ok) {
      ++errors;
      continue;  // the control loop stops using the rate once it is stale
    }
    imu_yaw_rate_.publish(io::Stamped<double>{sample.deg_per_s, io_.clock->now(), errors});
  }
}

std::uint64_t Sprayer::start_wheel_calibration(double run_distance_m) noexcept {
  if (io_.gnss == nullptr || io_.wheel == nullptr) return 0;
  wheel_calibration_distance_bits_.store(std::bit_cast<std::uint64_t>(run_distance_m));
  return wheel_calibration_requests_.fetch_add(1) + 1;
}

}  // namespace weedspray::daemon
