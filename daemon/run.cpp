// The daemon's main thread: picks the backends, starts the sprayer's threads, and runs the
// sd-event loop with the D-Bus service, signals (SIGTERM/SIGINT: safe exit, SIGHUP: reload),
// the alarm evaluation and state machine, the status snapshots and the systemd watchdog.
#include "daemon/run.hpp"

#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>
#include <systemd/sd-event.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <thread>

#include "control/flow_feedback.hpp"
#include "daemon/backends/backends.hpp"
#include "daemon/backends/emergency_write_handoff.hpp"
#include "daemon/backends/output_manifest.hpp"
#include "daemon/backends/pick_backends.hpp"
#include "daemon/bus/dbus_service.hpp"
#include "daemon/bus/status.hpp"
#include "daemon/bus/status_builder.hpp"
#include "daemon/config/config.hpp"
#include "daemon/config/live_reload.hpp"
#include "daemon/config/run_config.hpp"
#include "daemon/logging.hpp"
#include "daemon/records/run_marker.hpp"
#include "daemon/records/run_records.hpp"
#include "daemon/sprayer/calibrations.hpp"
#include "daemon/sprayer/live_view.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "daemon/supervision/alarm_catalog.hpp"
#include "daemon/supervision/alarm_log.hpp"
#include "daemon/supervision/alarms.hpp"
#include "daemon/supervision/exit_watch.hpp"
#include "daemon/supervision/loop_timing.hpp"
#include "daemon/supervision/state_machine.hpp"
#include "daemon/test_crash_hook.hpp"
#include "io/emergency_outputs.hpp"
#include "io/linux/cpu_latency_qos.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;
constexpr std::uint64_t kTickUsec = 50'000;  // 20 Hz main-loop tick
constexpr std::size_t kLatencyWindow = 1000;

double seconds(Nanos t) {
  return std::chrono::duration<double>(t).count();
}

Nanos from_seconds(double s) {
  return std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(s));
}

class Daemon final : public CommandHandler {
 public:
  Daemon(const Options& options, Config config)
      : options_(options),
        config_(std::move(config)),
        alarms_(config_.alarms),
        setpoint_mpa_(config_.pressure.setpoint_mpa) {}

  ~Daemon() override {
    // The outputs' descriptors close with the backends: a later fatal signal must not write to
    // whatever reuses those numbers.
    io::EmergencyOutputs::clear();
    if (tick_source_ != nullptr) sd_event_source_unref(tick_source_);
    for (auto* source : signal_sources_) sd_event_source_unref(source);
    live_view_.reset();  // answers a pending Snapshot while the bus is still there
    dbus_.reset();
    if (event_ != nullptr) sd_event_unref(event_);
  }

  // The safe writers outside this process: run() hands them the outputs, each tick keeps the
  // exit watcher running.
  void set_exit_watch(ExitWatch exit_watch) noexcept { exit_watch_.emplace(std::move(exit_watch)); }

  int run() {
    world_ = pick_backends(config_, options_, backends_);
    if (exit_watch_->has_watcher()) exit_watch_->hand_outputs();
    std::filesystem::create_directories(config_.daemon.state_dir);
    run_marker_.emplace(std::filesystem::path(config_.daemon.state_dir) / "running");
    // A fresh start begins from nothing, its last run's end included.
    previous_run_unfinished_ = run_marker_->previous_run_unfinished() && !world_->starts_afresh();
    if (previous_run_unfinished_)
      spdlog::warn(
          "the last run did not end in an orderly stop (a crash, kill -9, the watchdog or a "
          "power cut): the sprayer waits for Start whatever daemon.autostart says");
    records_.emplace(config_, world_->starts_afresh());
    calibrations_.emplace(config_, config_.daemon.state_dir, world_->delivered_litres());
    records_->open_log(config_);

    check(sd_event_default(&event_), "sd_event_default");
    for (int signal : {SIGTERM, SIGINT, SIGHUP}) {
      sd_event_source* source = nullptr;
      check(sd_event_add_signal(event_, &source, signal, &Daemon::on_signal, this),
            "sd_event_add_signal");
      signal_sources_.push_back(source);
    }
    if (!options_.no_bus) {
      try {
        dbus_ = std::make_unique<DbusService>(event_, options_.user_bus, *this);
      } catch (const std::exception& error) {
        if (!world_->runs_without_bus(error.what())) throw;
        config_.daemon.autostart = true;
      }
    }

    sprayer_ = std::make_unique<Sprayer>(config_, backends_);
    std::vector<int> first_nozzles;
    for (const auto& camera : config_.cameras) first_nozzles.push_back(camera.first_nozzle);
    live_view_ = std::make_unique<LiveView>(*sprayer_, std::move(first_nozzles));
    world_->start();
    request_cpu_wakeup_latency();
    sprayer_->start();
    output_watch_.emplace(backends_.output_devices());
    unsafe_outputs_ = sprayer_->safe_write_errors();
    for (const auto& warning : sprayer_->realtime_warnings()) {
      spdlog::warn("real-time priority not granted ({}); running at normal priority", warning);
    }
    start_time_ = backends_.clock->now();
    last_tick_time_ = start_time_;
    gnss_lost_fix_.emplace(start_time_, from_seconds(config_.gnss.lost_fix_timeout_s),
                           from_seconds(config_.gnss.first_fix_timeout_s));
    // [log] takes a restart: the writer keeps its own copy of the floor.
    const std::uint64_t records_floor_bytes =
        static_cast<std::uint64_t>(config_.log.min_free_mb) * 1'000'000;
    records_->start_writer(*sprayer_, records_floor_bytes);

    uint64_t watchdog_usec = 0;
    if (sd_watchdog_enabled(0, &watchdog_usec) > 0)
      watchdog_interval_ = Nanos(watchdog_usec * 1000 / 2);
    check(sd_event_add_time_relative(event_, &tick_source_, CLOCK_MONOTONIC, kTickUsec, 0,
                                     &Daemon::on_tick, this),
          "sd_event_add_time_relative");
    sd_event_source_set_enabled(tick_source_, SD_EVENT_ON);

    spdlog::info("weedsprayd running ({} nozzles, {} camera(s), config {})", config_.boom.nozzles,
                 config_.cameras.size(),
                 config_.files.empty() ? std::string("built-in defaults") : options_.config_path);
    const int r = sd_event_loop(event_);
    sd_notify(0, "STOPPING=1");
    shutdown();
    const int status = r < 0 ? 1 : exit_code_;
    if (status == 0) run_marker_->finish();
    return status;
  }

  // Called on every exit path: threads stopped, outputs forced safe, state persisted.
  void shutdown() noexcept {
    if (sprayer_) sprayer_->stop();
    if (live_view_) live_view_->cancel("weedsprayd is stopping");
    report_safe_writes(backends_.force_safe());
    report_timing();
    cpu_latency_ = {};
    if (world_) world_->finish();
    if (records_) {
      records_->stop_writer();
      records_->persist();
    }
  }

  // --- D-Bus commands (main thread) ---
  CommandResult start() override {
    if (calibrations_ && calibrations_->running())
      return {kErrorNotPermitted, "Start refused: a calibration runs (Stop cancels it)"};
    // The bus name appears before the loops have run a cycle: a Start then is kept, not refused.
    if (state_.state() == SprayerState::kStarting) {
      start_when_ready_ = true;
      spdlog::info("Start accepted: spraying as soon as the loops run");
      return {};
    }
    return request(StateEvent::kStart, "Start");
  }
  CommandResult stop() override {
    if (calibrations_ && calibrations_->cancel("Stop")) {
      publish_params();
      return {};
    }
    if (state_.state() == SprayerState::kStarting && start_when_ready_) {
      start_when_ready_ = false;
      return {};
    }
    return request(StateEvent::kStop, "Stop");
  }

  CommandResult set_pressure_setpoint(double mpa) override {
    constexpr double kMin = 0.05;
    const double max = std::min(1.0, config_.alarms.over_pressure_mpa);
    if (!(mpa >= kMin && mpa < max)) {
      char message[160];
      std::snprintf(message, sizeof message,
                    "pressure %.3g MPa outside %.3g..%.3g MPa (below alarms.over_pressure_mpa)",
                    mpa, kMin, max);
      return {kErrorInvalidArgument, message};
    }
    setpoint_mpa_ = mpa;
    spdlog::info("pressure set-point {:.3f} MPa", mpa);
    publish_params();
    return {};
  }

  CommandResult reload_config(ReloadReply reply) override {
    reload_waiters_.push_back(std::move(reply));
    if (!reload_job_) start_reload();  // else the next job, once this one is applied
    return {};
  }

  // The files are read and parsed and the model probed on a thread of its own (seconds for a
  // large model on a slow board), while the main loop goes on feeding the watchdog, judging
  // alarms and serving the bus; tick() applies the result. Callers that arrive meanwhile wait
  // for the next job, which reads the files as they are then.
  struct ReloadJob {
    std::vector<ReloadReply> waiters;
    std::optional<Config> config;
    std::string error;
    std::atomic<bool> done{false};
    std::jthread thread;  // last: joined before the rest goes
  };

  void start_reload() {
    auto job = std::make_unique<ReloadJob>();
    job->waiters = std::exchange(reload_waiters_, {});
    ReloadJob* running = job.get();
    job->thread = std::jthread([running, options = options_] {
      const std::chrono::milliseconds delay = test_reload_delay();
      if (delay.count() > 0) std::this_thread::sleep_for(delay);
      try {
        running->config = load_config_with_overrides(options);
      } catch (const std::exception& error) {  // ConfigError, or a conf.d that cannot be listed
        running->error = error.what();
      }
      running->done.store(true, std::memory_order_release);
    });
    reload_job_ = std::move(job);
  }

  void finish_reload() {
    if (!reload_job_ || !reload_job_->done.load(std::memory_order_acquire)) return;
    reload_job_->thread.join();
    const CommandResult result = reload_job_->config ? apply_reload(*reload_job_->config)
                                                     : refuse_reload(reload_job_->error);
    std::vector<ReloadReply> waiters = std::move(reload_job_->waiters);
    reload_job_.reset();
    for (auto& reply : waiters) {
      if (reply) reply(result);
    }
    if (!reload_waiters_.empty()) start_reload();
  }

  static CommandResult refuse_reload(const std::string& why) {
    spdlog::error("reload refused, running configuration kept: {}", why);
    return {kErrorConfig, why};
  }

  CommandResult apply_reload(const Config& fresh) {
    LiveReload reload;
    try {
      reload = apply_live_reload(config_, fresh);
    } catch (const ConfigError& error) {
      return refuse_reload(error.what());
    }
    if (reload.restart_needed) {
      spdlog::warn(
          "reload: changes outside [spray], [alarms], pressure.setpoint_mpa and "
          "[daemon] levels take effect after a restart");
    }
    for (const auto& key : reload.kept_limits) {
      spdlog::warn("reload: {} is a safety limit: restart required, running value kept", key);
    }
    config_ = std::move(reload.config);
    if (calibrations_) calibrations_->set_config(config_);
    setpoint_mpa_ = config_.pressure.setpoint_mpa;
    alarms_.set_thresholds(config_.alarms);
    set_log_level(config_.daemon.log_level);
    publish_params();
    spdlog::info("configuration reloaded from {}", options_.config_path);
    return {};
  }

  CommandResult clear_alarms() override {
    if (sprayer_ && !sprayer_->reset_estop())
      spdlog::warn("E-stop circuit still open: the stop stays latched (close it, then clear)");
    const AlarmMask cleared = alarms_.clear();
    if (sprayer_) sprayer_->resume_heartbeat();
    ++trip_reset_;
    for (std::size_t i = 0; i < kAlarmCount; ++i) {
      const auto id = static_cast<AlarmId>(i);
      if (cleared & alarm_bit(id)) {
        log_alarm_cleared(id, "sprayctl clear-alarms", logs_to_journal());
        if (dbus_) dbus_->alarm_cleared(std::string(alarm_name(id)).c_str());
      }
    }
    if (state_.state() == SprayerState::kFault)
      transition(StateEvent::kAlarmsCleared, "ClearAlarms");
    publish_params();
    return {};
  }

 private:
  static void check(int r, const char* what) {
    if (r < 0) throw std::runtime_error(std::string(what) + ": " + std::strerror(-r));
  }

  static int on_signal(sd_event_source*, const struct signalfd_siginfo* info, void* userdata) {
    auto& self = *static_cast<Daemon*>(userdata);
    if (info->ssi_signo == SIGHUP) {
      try {
        self.reload_config(nullptr);           // its outcome is logged
      } catch (const std::exception& error) {  // never through sd-event's C frames
        spdlog::error("reload: {}", error.what());
      }
      return 0;
    }
    spdlog::info("signal {}: stopping", info->ssi_signo);
    sd_event_exit(self.event_, 0);
    return 0;
  }

  static int on_tick(sd_event_source* source, uint64_t, void* userdata) {
    auto& self = *static_cast<Daemon*>(userdata);
    try {
      self.tick();
    } catch (const std::exception& error) {
      spdlog::critical("main loop: {}", error.what());
      self.exit_code_ = 1;
      sd_event_exit(self.event_, 1);
    }
    sd_event_source_set_time_relative(source, kTickUsec);
    sd_event_source_set_enabled(source, SD_EVENT_ON);
    return 0;
  }

  CommandResult request(StateEvent event, const char* what) {
    const Transition t = transition(event, what);
    if (!t.accepted) return {kErrorNotPermitted, std::string(what) + " refused: " + t.reason};
    return {};
  }

  Transition transition(StateEvent event, const char* cause) {
    const Transition t = state_.handle(event);
    if (t.accepted && t.from != t.to) {
      spdlog::info("state {} -> {} ({})", to_string(t.from), to_string(t.to), cause);
      // A calibration runs only in Idle: ended here, so the parameters published below close
      // its valves and stop the pump in this tick, not the next.
      if (t.to != SprayerState::kIdle && calibrating()) calibrations_->cancel(cause);
      publish_params();
      const std::string status = "STATUS=" + std::string(to_string(t.to));
      sd_notify(0, status.c_str());
    }
    return t;
  }

  // Commands show their effect on the bus at once, not at the next status period.
  void refresh_status() {
    if (dbus_ && sprayer_) dbus_->update(make_status(sprayer_->pressure(), sprayer_->control()));
  }

  void publish_params() {
    LiveParams params = live_params_from(config_);
    params.setpoint_mpa = setpoint_mpa_;
    // A calibration (in Idle) runs the pump for its own valves.
    params.pump_enabled = state_.pump_enabled(calibrating());
    params.valves_enabled = state_.valves_enabled();
    params.trip_reset = trip_reset_;
    if (calibrations_) calibrations_->apply(params);
    sprayer_->set_params(params);
    refresh_status();
  }

  bool calibrating() const noexcept { return calibrations_ && calibrations_->running(); }

  void tick() {
    run_requested_test_fault();
    const Nanos now = backends_.clock->now();
    const double t = seconds(now - start_time_);
    world_->step(t);
    const PressureStatus pressure = sprayer_->pressure();
    const ControlStatus control = sprayer_->control();
    report_stalls(pressure);

    if (state_.state() == SprayerState::kStarting && pressure.cycles > 0 && control.cycles > 0) {
      transition(StateEvent::kSetupDone, "loops running");
      sd_notify(0, "READY=1");
      if (config_.daemon.autostart && previous_run_unfinished_)
        spdlog::warn("daemon.autostart skipped after an unfinished run: send Start");
      else if (config_.daemon.autostart)
        transition(StateEvent::kStart, "daemon.autostart");
      if (start_when_ready_) transition(StateEvent::kStart, "Start while starting up");
      start_when_ready_ = false;
    }
    if (backends_.key != nullptr) {
      const io::DigitalInputSample key = backends_.key->sample();
      if (key.change_count != key_changes_) {
        key_changes_ = key.change_count;
        if (key.active) transition(StateEvent::kKeyPressed, "start/stop key");
      }
    }
    drain_latencies();
    live_view_->poll(now);
    if (calibrations_ && calibrations_->update(calibration_context())) publish_params();
    finish_reload();
    evaluate_alarms(now, pressure, control);
    heartbeat(now, pressure, control);

    const double status_period = 1.0 / config_.daemon.status_max_rate_hz;
    if (t - last_status_s_ >= status_period) {
      last_status_s_ = t;
      const Status status = make_status(pressure, control);
      if (dbus_) dbus_->update(status);
      world_->status_published(status, t);
    }
    if (t - last_persist_s_ >= 60.0) {
      last_persist_s_ = t;
      records_->persist();
    }
    if (options_.run_seconds > 0 && t >= options_.run_seconds) sd_event_exit(event_, 0);
  }

  CommandResult snapshot(std::uint32_t camera, SnapshotReply reply) override {
    if (!live_view_) return {kErrorUnavailable, "Snapshot: the cameras are not running yet"};
    return live_view_->request(camera, backends_.clock->now(), std::move(reply));
  }

  CommandResult calibrate_wheel(double run_distance_m, std::uint64_t& request) override {
    if (!(run_distance_m >= 10.0 && run_distance_m <= 5000.0)) {
      return {kErrorInvalidArgument,
              "CalibrateWheel: the straight run must be 10..5000 m (100 m or more for an "
              "autonomous receiver, 1.5 m position error at each end)"};
    }
    if (!sprayer_) return {kErrorUnavailable, "CalibrateWheel: the sprayer is not running yet"};
    request = sprayer_->start_wheel_calibration(run_distance_m);
    if (request == 0) {
      return {kErrorNotPermitted,
              "CalibrateWheel: needs a GNSS receiver ([gnss] enabled = true) and a wheel sensor "
              "(wheel.source = \"pulses\")"};
    }
    spdlog::info("wheel calibration {} started: {:.0f} m straight run", request, run_distance_m);
    return {};
  }

  CalibrationContext calibration_context() const {
    CalibrationContext c;
    c.idle = state_.state() == SprayerState::kIdle;
    c.have_meter = backends_.flow != nullptr;
    // The pulse count with the control loop's own time of it: under load the main loop's tick
    // comes late, and its clock would stretch or shrink a counted window.
    const ControlStatus control = sprayer_ ? sprayer_->control() : ControlStatus{};
    c.now_s = seconds((control.cycles > 0 ? control.time : backends_.clock->now()) - start_time_);
    c.pulses = control.flow_pulses;
    c.setpoint_mpa = setpoint_mpa_;
    return c;
  }

  // A calibration's command, and its valves to the loops when it was taken.
  CommandResult calibration_command(const std::function<CommandResult(Calibrations&)>& command) {
    if (!calibrations_ || !sprayer_) return {kErrorUnavailable, "the sprayer is not running yet"};
    const CommandResult result = command(*calibrations_);
    if (result.ok()) publish_params();
    return result;
  }

  CommandResult start_catch_test(double seconds) override {
    return calibration_command(
        [&](Calibrations& c) { return c.start_catch_test(seconds, calibration_context()); });
  }
  CommandResult calibrate_meter(double volume_l) override {
    return calibration_command([&](Calibrations& c) { return c.calibrate_meter(volume_l); });
  }
  CommandResult calibrate_nozzles() override {
    return calibration_command(
        [&](Calibrations& c) { return c.calibrate_nozzles(calibration_context()); });
  }

  void bus_lost() override {
    spdlog::critical(
        "D-Bus connection lost: sprayctl can no longer stop the sprayer, so it stops now "
        "(valves closed, pump off) and exits for systemd to restart it Idle");
    exit_code_ = 1;
    sd_event_exit(event_, 1);
  }

  CommandResult inject_sim_fault(const std::string& name) override {
    return world_->inject_fault(name);
  }

  void drain_latencies() {
    while (auto latency = sprayer_->latencies().try_pop()) {
      if (latencies_.size() < kLatencyWindow) {
        latencies_.push_back(*latency);
      } else {
        latencies_[latency_next_] = *latency;
      }
      latency_next_ = (latency_next_ + 1) % kLatencyWindow;
    }
  }

  double latency_p99() const {
    if (latencies_.empty()) return 0;
    std::vector<float> sorted = latencies_;
    const auto k = static_cast<std::size_t>(0.99 * static_cast<double>(sorted.size() - 1));
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(k), sorted.end());
    return sorted[k];
  }

  // What one occurrence of an alarm measured, for its log entry (the catalog holds what it means
  // and what to do: daemon/supervision/alarm_catalog.cpp).
  std::string alarm_detail(AlarmId id, const AlarmInputs& in, const PressureStatus& pressure,
                           const ControlStatus& control, const std::string& output_failures,
                           const std::string& vision_failures) const {
    switch (id) {
      case AlarmId::kOutputWriteFailed:
        return output_failures + "; every other output driven safe";
      case AlarmId::kFlowValvesClosed:
        return fmt::format(
            "{:.3f} L/min through the meter with every valve commanded closed for "
            "{:.1f} s",
            in.flow_l_per_min, in.valves_closed_s);
      case AlarmId::kPressureSensorFault:
        return fmt::format("loop current {:.2f} mA", pressure.current_ma);
      case AlarmId::kOverPressure:
        return fmt::format("{:.3f} MPa, trip at {:.3f} MPa", pressure.pressure_mpa,
                           config_.alarms.over_pressure_mpa);
      case AlarmId::kEstop: {
        const EstopStatus estop = sprayer_->estop();
        return fmt::format(
            "valves and pump written safe {:.3f} ms after the edge (largest {:.3f} ms), {} safe "
            "write(s) refused; latched until the circuit is closed and the alarms are cleared",
            std::chrono::duration<double, std::milli>(estop.last_reaction).count(),
            std::chrono::duration<double, std::milli>(estop.max_reaction).count(),
            estop.safe_write_errors);
      }
      case AlarmId::kControlOverruns:
        return fmt::format("{} deadline misses while spraying in the last second; {}",
                           overruns_last_second_,
                           timing_report_line(timing_input(pressure, control)));
      case AlarmId::kGnssFixLost: {
        // What the control loop uses without a fix (it switched on its own, at the same timeout).
        GroundSpeedInputs without_fix;
        without_fix.source = parse_speed_source(config_.speed.source).value_or(SpeedSource::kWheel);
        without_fix.wheel_wired = backends_.wheel != nullptr;
        return fmt::format("no usable fix for {} s; gpsd at {}:{} {}; speed from {}",
                           config_.gnss.lost_fix_timeout_s, config_.gnss.host, config_.gnss.port,
                           sprayer_->gnss_link().connected ? "connected: the receiver has no fix"
                                                           : "not reachable",
                           to_string(select_ground_speed(without_fix).used));
      }
      case AlarmId::kNozzleFlowFault: {
        const int n = control.nozzle_flow_fault;
        const double ratio = n >= 0 ? control.nozzle_flow_ratio[static_cast<std::size_t>(n)] : 1.0;
        return fmt::format("nozzle {}: {}, its flow {:.2f} of its baseline", n,
                           control.nozzle_flow_fault_low ? "blocked" : "over (worn or stuck open)",
                           ratio);
      }
      case AlarmId::kCalibrationDrift: {
        const double ratio = control.calibration_ratio;
        const double c = control.flow_trim_correction;
        const control::FlowTrimConfig trim;
        return fmt::format(
            "the line meter has read {:.1f} % {} than the calibrated nozzles promise at the "
            "commanded duties for {} s; the flow trim at x{:.3f}{}",
            std::abs(ratio - 1.0) * 100.0, ratio > 1.0 ? "more" : "less",
            config_.alarms.calibration_drift_hold_s, c,
            c <= trim.min_correction || c >= trim.max_correction
                ? " is at its limit: the dose is NOT held"
                : " corrects the modulated nozzles by the boom's common change");
      }
      case AlarmId::kRecordsDiskFull:
        return fmt::format("log.min_free_mb = {} MB in {}", config_.log.min_free_mb,
                           records_->log_dir().string());
      case AlarmId::kVisionModelFailed:
        return vision_failures;
      case AlarmId::kExitWatcherLost:
        return exit_watch_->lost_because();
      case AlarmId::kTankLow:
      case AlarmId::kTankEmpty:
        return fmt::format("{:.0f} %", in.tank_level_pct);
      default:
        return {};
    }
  }

  void evaluate_alarms(Nanos now, const PressureStatus& pressure, const ControlStatus& control) {
    AlarmInputs in;
    in.now = now;
    in.spraying = state_.state() == SprayerState::kSpraying;
    in.pump_commanded = state_.pump_enabled(calibrating());
    in.open_fraction = control.open_fraction;
    in.pressure_valid = pressure.cycles == 0 || pressure.sensor_ok;
    in.pressure_mpa = pressure.pressure_mpa;
    in.over_pressure_trip = pressure.tripped;
    in.sensor_current_ma = pressure.current_ma;
    in.flow_l_per_min = control.flow_l_per_min;
    // From the control loop's own cycles: a valve open between two ticks still counts.
    if (control.cycles > 0 && control.open_fraction == 0.0)
      in.valves_closed_s = seconds(control.time - control.valves_last_open);
    in.tank_enabled =
        backends_.tank != nullptr && (config_.modbus.enabled || world_->tank_always_read());
    const io::TankLevelSample tank = sprayer_->tank();
    in.tank_valid = tank.ok;
    in.tank_level_pct = tank.level_pct;
    if (tank.ok) tank_last_ok_ = tank.time;
    in.tank_last_ok = std::max(tank_last_ok_, start_time_);
    in.camera_expected = state_.state() == SprayerState::kSpraying;
    in.last_frame_time = now;
    double lead_m = 1e9;
    for (std::size_t i = 0; i < sprayer_->camera_count(); ++i) {
      const CameraStatus camera = sprayer_->camera(i);
      const auto footprint = sprayer_->footprint(i);
      in.last_frame_time =
          std::min(in.last_frame_time, std::max(camera.last_frame_time, spraying_since_));
      lead_m = std::min(lead_m, footprint.near_m + config_.cameras[i].distance_to_nozzles_m);
    }
    in.speed_m_per_s = control.speed_m_per_s;
    in.expected_frame_interval_s = 0;
    if (world_->frames_per_footprint() && control.speed_m_per_s > 0.05 &&
        sprayer_->camera_count() > 0) {
      const auto footprint = sprayer_->footprint(0);
      in.expected_frame_interval_s = (footprint.far_m - footprint.near_m) / control.speed_m_per_s;
    }
    in.coverage_gap = control.coverage_gaps != coverage_gaps_seen_;
    coverage_gaps_seen_ = control.coverage_gaps;
    in.vision_latency_s = control.last_latency_ms / 1e3;
    in.lead_distance_m = lead_m;
    // Only misses while spraying count: a late wake in Idle moves no liquid.
    const std::uint64_t misses = total_misses(pressure, control);
    const bool spraying = state_.state() == SprayerState::kSpraying;
    if (spraying) {
      misses_while_spraying_ += misses - misses_seen_;
      spraying_seconds_ += seconds(now - last_tick_time_);
    }
    misses_seen_ = misses;
    last_tick_time_ = now;
    if (seconds(now - overrun_window_start_) >= 1.0) {
      overruns_last_second_ = misses_while_spraying_ - overruns_at_window_start_;
      overruns_at_window_start_ = misses_while_spraying_;
      overrun_window_start_ = now;
    }
    in.overruns_last_second = overruns_last_second_;
    const std::string vision_failures = sprayer_->vision_failures();
    in.vision_model_failed = !vision_failures.empty();
    const std::string output_failures = check_outputs();
    in.output_write_failed = !output_failures.empty();
    in.exit_watcher_lost = !exit_watch_->running(now);
    in.gnss_fix_lost = backends_.gnss != nullptr && gnss_lost_fix_->lost(sprayer_->gnss(), now);
    // Not from a status older than the last ClearAlarms (the detector restarts on it).
    in.nozzle_flow_fault =
        control.nozzle_flow_fault >= 0 && control.nozzle_health_reset == trip_reset_;
    in.calibration_ratio = control.calibration_ratio;
    const EstopStatus estop = sprayer_->estop();
    in.estop_latched = estop.latched;
    in.records_at_risk = records_->at_risk();

    const AlarmMask raised = alarms_.evaluate(in);
    for (std::size_t i = 0; i < kAlarmCount; ++i) {
      const auto id = static_cast<AlarmId>(i);
      if (!(alarms_.cleared_by_itself() & alarm_bit(id))) continue;
      const std::string name(alarm_name(id));
      log_alarm_cleared(id, "its condition ended", logs_to_journal());
      if (dbus_) dbus_->alarm_cleared(name.c_str());
    }
    for (std::size_t i = 0; i < kAlarmCount; ++i) {
      const auto id = static_cast<AlarmId>(i);
      if (!(raised & alarm_bit(id))) continue;
      const std::string name(alarm_name(id));
      log_alarm_raised(id,
                       alarm_detail(id, in, pressure, control, output_failures, vision_failures),
                       logs_to_journal());
      if (dbus_) dbus_->alarm_raised(name.c_str());
    }
    if (alarms_.fault_latched() && state_.state() != SprayerState::kFault) {
      transition(StateEvent::kFault, "alarm");
    }
    // A latched Fault stops the heartbeat: the external relay cuts valves and pump whatever the
    // outputs do. ClearAlarms lets it beat again.
    if (alarms_.fault_latched()) sprayer_->stop_heartbeat();
    if (state_.state() == SprayerState::kSpraying) {
      if (!was_spraying_) spraying_since_ = now;
      was_spraying_ = true;
    } else {
      was_spraying_ = false;
    }
    const bool any = alarms_.active() != 0;
    const auto count_failure = [this](OutputRole role, int result) {
      if (result != 0) ++main_thread_write_failures_[static_cast<std::size_t>(role)];
    };
    if (backends_.led != nullptr)
      count_failure(OutputRole::kLed, backends_.led->write(any ? 1 : 0));
    if (backends_.buzzer != nullptr)
      count_failure(OutputRole::kBuzzer, backends_.buzzer->write(alarms_.fault_latched() ? 1 : 0));
  }

  // The outputs' failed writes since the last tick, and the safe writes still failing (retried
  // here while in Fault, when every output is meant to be safe): "" when all is well, else a
  // message naming each output (the output_write_failed alarm).
  std::string check_outputs() {
    OutputWriteCounters counters = sprayer_->output_write_counters();
    for (std::size_t i = 0; i < kOutputRoleCount; ++i) {
      counters.failed_writes[i] += main_thread_write_failures_[i];
      // An output that refused a write may be left in any state (a valve stuck open): it is
      // written safe again from here once in Fault, and until that succeeds.
      if (counters.failed_writes[i] != failed_writes_seen_[i]) rewrite_safe_[i] = true;
      failed_writes_seen_[i] = counters.failed_writes[i];
    }
    if (state_.state() == SprayerState::kFault) {
      for (std::size_t i = 0; i < kOutputRoleCount; ++i) {
        if (!rewrite_safe_[i] && unsafe_outputs_[i] == 0) continue;
        const bool was_unsafe = unsafe_outputs_[i] != 0;
        unsafe_outputs_[i] = backends_.force_safe(static_cast<OutputRole>(i));
        if (unsafe_outputs_[i] != 0) continue;
        rewrite_safe_[i] = false;
        if (was_unsafe)
          spdlog::info("{} written safe again", output_role_name(static_cast<OutputRole>(i)));
      }
    }
    for (std::size_t i = 0; i < kOutputRoleCount; ++i) {
      counters.unsafe_error[i] = -unsafe_outputs_[i];
      // Tolerated failures are no fault, but a rising count says the bus is getting worse.
      const std::uint64_t tolerated = counters.tolerated_failures[i] - tolerated_seen_[i];
      if (tolerated > 0)
        spdlog::warn(
            "{}: {} failed write(s) superseded by the next ({} total; [dac] "
            "write_failures_tolerated = {} in a row)",
            output_role_name(static_cast<OutputRole>(i)), tolerated, counters.tolerated_failures[i],
            config_.dac.write_failures_tolerated);
      tolerated_seen_[i] = counters.tolerated_failures[i];
    }
    return output_watch_->update(counters);
  }

  std::uint64_t total_overruns(const PressureStatus& pressure, const ControlStatus& control) const {
    return pressure.overruns + control.overruns + sprayer_->pwm().late_edges +
           sprayer_->analog_io().overruns;
  }

  // Lateness that affects spraying (alarms.timing_tolerance_ms), in any loop.
  std::uint64_t total_misses(const PressureStatus& pressure, const ControlStatus& control) const {
    return pressure.misses + control.misses + sprayer_->pwm().missed_edges;
  }

  // The loops' cross-watch acted: say so (the late wakes also count as misses).
  void report_stalls(const PressureStatus& pressure) {
    const std::uint64_t pressure_stalls = sprayer_->pressure_loop_stalls();
    if (pressure_stalls != pressure_stalls_seen_) {
      spdlog::error("pressure loop stalled with the pump on: the valve thread switched it off");
      pressure_stalls_seen_ = pressure_stalls;
    }
    if (pressure.valve_thread_stalls != valve_stalls_seen_) {
      spdlog::error("valve thread stalled: pump off and return valve open until it runs again");
      valve_stalls_seen_ = pressure.valve_thread_stalls;
    }
  }

  // A PM QoS request keeps the CPUs out of slow idle states while the loops run (see
  // io/linux/cpu_latency_qos.hpp for what it fixes).
  void request_cpu_wakeup_latency() {
    const int us = config_.daemon.cpu_wakeup_latency_us;
    if (us < 0) {
      cpu_latency_state_ = "none (daemon.cpu_wakeup_latency_us = -1)";
      return;
    }
    cpu_latency_ = io::hw::CpuLatencyRequest(us);
    if (cpu_latency_.active()) {
      cpu_latency_state_ = std::to_string(us) + " us";
      spdlog::info("CPU wake-up latency held at {} us while running (PM QoS)", us);
    } else {
      cpu_latency_state_ = "not held: " + cpu_latency_.error();
      spdlog::warn(
          "CPU wake-up latency request not held ({}): real-time loops may wake late from idle "
          "(give the service user write access to /dev/cpu_dma_latency; see README)",
          cpu_latency_.error());
    }
  }

  TimingReportInput timing_input(const PressureStatus& pressure,
                                 const ControlStatus& control) const {
    TimingReportInput in;
    in.timing = &sprayer_->timing();
    const io::ValvePwmStats pwm = sprayer_->pwm();
    in.valve_edges = {pwm.skipped_edges, pwm.missed_edges};
    in.pressure_loop = {pressure.overruns, pressure.misses};
    in.control_loop = {control.overruns, control.misses};
    in.converter_overruns = sprayer_->analog_io().overruns;
    in.misses_while_spraying = misses_while_spraying_;
    in.seconds = seconds(backends_.clock->now() - start_time_);
    in.spraying_seconds = spraying_seconds_;
    in.realtime = sprayer_->realtime_warnings().empty();
    in.cpu_latency_request = cpu_latency_state_;
    return in;
  }

  // At exit: every output safe, or each one that is not named (and the exit status says so,
  // so systemd's ExecStopPost and the journal both see it).
  void report_safe_writes(const SafeWriteErrors& errors) noexcept {
    try {
      const auto devices = backends_.output_devices();
      bool all_safe = true;
      for (std::size_t i = 0; i < kOutputRoleCount; ++i) {
        if (errors[i] == 0) continue;
        all_safe = false;
        spdlog::critical("output NOT safe: {} ({}): safe value not written: {}",
                         output_role_name(static_cast<OutputRole>(i)), devices[i],
                         std::strerror(-errors[i]));
      }
      if (all_safe) {
        spdlog::info("outputs safe: valves closed, pump off, return valve open");
      } else {
        exit_code_ = 1;
      }
    } catch (...) {
      exit_code_ = 1;
    }
  }

  void report_timing() noexcept {
    if (!sprayer_ || !backends_.clock) return;
    try {
      const TimingReportInput in = timing_input(sprayer_->pressure(), sprayer_->control());
      spdlog::info("real-time timing: {}", timing_report_line(in));
      if (options_.timing_report.empty()) return;
      const std::string json = timing_report_json(in);
      if (options_.timing_report == "-") {
        std::printf("%s\n", json.c_str());
        std::fflush(stdout);
      } else if (!(std::ofstream(options_.timing_report) << json << '\n')) {
        spdlog::error("timing report: cannot write {}", options_.timing_report);
      }
    } catch (const std::exception& error) {
      spdlog::error("timing report: {}", error.what());
    }
  }

  // The watchdog is fed only while the real-time loops make progress.
  void heartbeat(Nanos now, const PressureStatus& pressure, const ControlStatus& control) {
    if (watchdog_interval_.count() == 0 || now - last_watchdog_ < watchdog_interval_) return;
    const std::uint64_t valve_wakes = sprayer_->pwm().wakes;
    if (pressure.cycles == heartbeat_pressure_ || control.cycles == heartbeat_control_ ||
        valve_wakes == heartbeat_valves_) {
      spdlog::error("real-time loops stalled: watchdog not fed");
      return;
    }
    heartbeat_pressure_ = pressure.cycles;
    heartbeat_control_ = control.cycles;
    heartbeat_valves_ = valve_wakes;
    last_watchdog_ = now;
    sd_notify(0, "WATCHDOG=1");
  }

  Status make_status(const PressureStatus& pressure, const ControlStatus& control) const {
    return build_status({config_, backends_, *sprayer_, state_.state(), setpoint_mpa_, alarms_,
                         records_->totals(), latency_p99(), total_overruns(pressure, control),
                         calibrations_ ? &*calibrations_ : nullptr},
                        pressure, control);
  }

  Options options_;
  Config config_;
  Backends backends_;
  std::unique_ptr<WorldDriver> world_;  // around backends_: a simulated world, or none
  std::unique_ptr<Sprayer> sprayer_;
  std::unique_ptr<LiveView> live_view_;  // main thread; before sprayer_ in destruction
  StateMachine state_;
  AlarmEvaluator alarms_;
  std::unique_ptr<DbusService> dbus_;
  sd_event* event_ = nullptr;
  sd_event_source* tick_source_ = nullptr;
  std::vector<sd_event_source*> signal_sources_;
  std::optional<RunRecords> records_;         // from run() on; its writer drains sprayer_'s records
  std::optional<Calibrations> calibrations_;  // from run() on
  double setpoint_mpa_;
  std::uint64_t trip_reset_ = 0;
  std::uint64_t key_changes_ = 0;
  std::uint64_t coverage_gaps_seen_ = 0;
  Nanos start_time_{};
  Nanos tank_last_ok_{};
  std::optional<LostFixWatch> gnss_lost_fix_;  // from start_time_ on
  Nanos spraying_since_{};
  bool was_spraying_ = false;
  Nanos overrun_window_start_{};
  std::uint64_t overruns_at_window_start_ = 0;
  std::uint64_t overruns_last_second_ = 0;
  std::uint64_t misses_seen_ = 0;
  std::uint64_t misses_while_spraying_ = 0;
  double spraying_seconds_ = 0;
  Nanos last_tick_time_{};
  io::hw::CpuLatencyRequest cpu_latency_;
  std::string cpu_latency_state_ = "none";
  Nanos watchdog_interval_{0};
  Nanos last_watchdog_{};
  std::uint64_t heartbeat_pressure_ = 0;
  std::uint64_t heartbeat_control_ = 0;
  std::uint64_t heartbeat_valves_ = 0;
  std::uint64_t pressure_stalls_seen_ = 0;
  std::uint64_t valve_stalls_seen_ = 0;
  std::vector<float> latencies_;
  std::size_t latency_next_ = 0;
  double last_status_s_ = -1e9;
  double last_persist_s_ = 0;
  int exit_code_ = 0;
  std::optional<RunMarker> run_marker_;  // present once the state folder is set up
  bool previous_run_unfinished_ = false;
  std::optional<OutputWriteWatch> output_watch_;
  SafeWriteErrors unsafe_outputs_{};  // -errno of safe writes that failed and still do
  std::array<std::uint64_t, kOutputRoleCount> main_thread_write_failures_{};
  std::array<std::uint64_t, kOutputRoleCount> failed_writes_seen_{};
  std::array<std::uint64_t, kOutputRoleCount> tolerated_seen_{};
  std::array<bool, kOutputRoleCount> rewrite_safe_{};  // refused a write: write it safe in Fault
  bool start_when_ready_ = false;                      // Start arrived while Starting
  std::vector<ReloadReply> reload_waiters_;            // asked for a reload not yet started
  std::unique_ptr<ReloadJob> reload_job_;
  std::optional<ExitWatch> exit_watch_;
};

}  // namespace

int write_safe_outputs(const Options& options) {
  return write_safe_outputs(options.config_path, options.output_manifest,
                            "weedsprayd --safe-outputs");
}

int run_daemon(const Options& options) {
  // Before any thread or output exists: a fatal signal or std::terminate from here on writes
  // the registered outputs safe (io/emergency_outputs.hpp).
#ifndef WEEDSPRAY_SELFTEST_NO_FAILSAFE  // only the HIL harness's self-test builds without it
  io::install_fatal_exit_handlers();
#endif
  RunConfig run;
  try {
    run = load_run_config(options);
  } catch (const ConfigError& error) {
    std::fprintf(stderr, "weedsprayd: %s\n", error.what());
    return 1;
  }
  setup_logging(run.config.daemon.log_level);
  for (const auto& warning : run.warnings) spdlog::warn("{}", warning);
  if (install_test_crash_hook())
    spdlog::warn("test crash hook enabled (WEEDSPRAY_TEST_CRASH_HOOK)");
  if (!run.note.empty()) spdlog::info("{}", run.note);
  // Block the signals sd-event handles before any thread exists, so every thread inherits the
  // mask and they arrive only through the event loop.
  sigset_t signals;
  sigemptyset(&signals);
  for (int signal : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&signals, signal);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  if (io::lock_memory() != 0) spdlog::info("memory not locked (mlockall not permitted)");

  std::optional<ExitWatch> exit_watch = ExitWatch::arm(run.config, options);
  if (!exit_watch) return 1;
  Daemon daemon(options, std::move(run.config));
  daemon.set_exit_watch(std::move(*exit_watch));
  try {
    return daemon.run();
  } catch (const std::exception& error) {
    spdlog::critical("fatal: {}", error.what());
    daemon.shutdown();
    return 1;
  }
}

}  // namespace weedspray::daemon
