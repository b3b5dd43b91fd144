// SPDX-License-Identifier: Apache-2.0
// The daemon's main thread, as its lifecycle. run_daemon() sets up the process (configuration,
// logging, signals, memory, the safe writers outside it); Daemon::run() starts each part in
// order, runs the sd-event loop (D-Bus, SIGTERM/SIGINT: safe exit, SIGHUP: reload, the 20 Hz
// tick) and shutdown() ends them in reverse. Each part is a job of its own: the backends and
// the world around them (backends/), the real-time threads (sprayer/), the operating state,
// alarms, loop health, outputs and exit watcher (supervision/), the records (records/), the
// commands and status (bus/), the reloads (config/).
#include "daemon/run.hpp"

#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>
#include <systemd/sd-event.h>

#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>

#include "daemon/backends/backends.hpp"
#include "daemon/backends/pick_backends.hpp"
#include "daemon/bus/commands.hpp"
#include "daemon/bus/dbus_service.hpp"
#include "daemon/bus/status_builder.hpp"
#include "daemon/config/config_reloads.hpp"
#include "daemon/config/run_config.hpp"
#include "daemon/logging.hpp"
#include "daemon/records/run_marker.hpp"
#include "daemon/records/run_records.hpp"
#include "daemon/sprayer/live_view.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "daemon/supervision/alarm_watch.hpp"
#include "daemon/supervision/exit_watch.hpp"
#include "daemon/supervision/loop_health.hpp"
#include "daemon/supervision/memory_residency.hpp"
#include "daemon/supervision/operation.hpp"
#include "daemon/supervision/output_checks.hpp"
#include "daemon/test_crash_hook.hpp"
#include "io/emergency_outputs.hpp"

namespace weedspray::daemon {
namespace {

constexpr std::uint64_t kTickUsec = 50'000;  // 20 Hz main-loop tick

double seconds(Nanos t) {
  return std::chrono::duration<double>(t).count();
}

void check(int r, const char* what) {
  if (r < 0) throw std::runtime_error(std::string(what) + ": " + std::strerror(-r));
}

class Daemon final {
 public:
  Daemon(const Options& options, Config config, ExitWatch exit_watch)
      : options_(options),
        config_(std::move(config)),
        operation_(config_, backends_),
        alarms_(config_.alarms),
        reloads_(options_, config_, operation_, alarms_.alarms()),
        exit_watch_(std::move(exit_watch)) {}

  ~Daemon() {
    // The outputs' descriptors close with the backends: a later fatal signal must not write to
    // whatever reuses those numbers.
    io::EmergencyOutputs::clear();
    if (tick_source_ != nullptr) sd_event_source_unref(tick_source_);
    for (auto* source : signal_sources_) sd_event_source_unref(source);
    live_view_.reset();  // answers a pending Snapshot while the bus is still there
    dbus_.reset();
    if (event_ != nullptr) sd_event_unref(event_);
  }

  int run() {
    world_ = pick_backends(config_, options_, backends_);
    if (exit_watch_.has_watcher()) exit_watch_.hand_outputs();
    open_records();
    listen_for_signals();
    connect_bus();
    start_sprayer();
    start_ticks();
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
    if (!OutputChecks::report_safe_writes(backends_, backends_.force_safe())) exit_code_ = 1;
    if (sprayer_ && backends_.clock)
      loops_.report_timing(*sprayer_, backends_.clock->now(), options_.timing_report);
    loops_.release_cpu_wakeup_latency();
    if (world_) world_->finish();
    if (records_) {
      records_->stop_writer();  // joins after draining
      records_->persist();
    }
  }

 private:
  // The state folder: the run marker, the totals, the calibrations and the as-applied log.
  void open_records() {
    std::filesystem::create_directories(config_.daemon.state_dir);
    run_marker_.emplace(std::filesystem::path(config_.daemon.state_dir) / "running");
    // A fresh start begins from nothing, its last run's end included.
    previous_run_unfinished_ = run_marker_->previous_run_unfinished() && !world_->starts_afresh();
    if (previous_run_unfinished_)
      spdlog::warn(
          "the last run did not end in an orderly stop (a crash, kill -9, the watchdog or a "
          "power cut): the sprayer waits for Start whatever daemon.autostart says");
    records_.emplace(config_, world_->starts_afresh());
    operation_.load_calibrations(world_->delivered_litres());
    records_->open_log(config_);
  }

  void listen_for_signals() {
    check(sd_event_default(&event_), "sd_event_default");
    for (int signal : {SIGTERM, SIGINT, SIGHUP}) {
      sd_event_source* source = nullptr;
      check(sd_event_add_signal(event_, &source, signal, &Daemon::on_signal, this),
            "sd_event_add_signal");
      signal_sources_.push_back(source);
    }
  }

  void connect_bus() {
    commands_.emplace(CommandTargets{config_, backends_, operation_, alarms_.alarms(), reloads_,
                                     *world_, [this] { stop_loop(1); }});
    if (options_.no_bus) return;
    try {
      dbus_ = std::make_unique<DbusService>(event_, options_.user_bus, *commands_);
      commands_->set_bus(dbus_.get());
    } catch (const std::exception& error) {
      if (!world_->runs_without_bus(error.what())) throw;
      config_.daemon.autostart = true;  // nothing could send Start
    }
  }

  void start_sprayer() {
    sprayer_ = std::make_unique<Sprayer>(config_, backends_);
    std::vector<int> first_nozzles;
    for (const auto& camera : config_.cameras) first_nozzles.push_back(camera.first_nozzle);
    live_view_ = std::make_unique<LiveView>(*sprayer_, std::move(first_nozzles));
    commands_->attach(*sprayer_, *live_view_);
    world_->start();
    loops_.request_cpu_wakeup_latency(config_.daemon.cpu_wakeup_latency_us);
    sprayer_->start();
    outputs_.start(backends_, sprayer_->safe_write_errors());
    for (const auto& warning : sprayer_->realtime_warnings()) {
      spdlog::warn("real-time priority not granted ({}); running at normal priority", warning);
    }
    start_time_ = backends_.clock->now();
    operation_.attach(*sprayer_, start_time_, [this] { refresh_status(); });
    alarms_.start(start_time_, config_.gnss);
    loops_.start(start_time_);
    // [log] takes a restart: the writer keeps its own copy of the floor.
    records_->start_writer(*sprayer_,
                           static_cast<std::uint64_t>(config_.log.min_free_mb) * 1'000'000);
  }

  void start_ticks() {
    check(sd_event_add_time_relative(event_, &tick_source_, CLOCK_MONOTONIC, kTickUsec, 0,
                                     &Daemon::on_tick, this),
          "sd_event_add_time_relative");
    sd_event_source_set_enabled(tick_source_, SD_EVENT_ON);
  }

  void stop_loop(int code) {
    exit_code_ = code;
    sd_event_exit(event_, code);
  }

  static int on_signal(sd_event_source*, const struct signalfd_siginfo* info, void* userdata) {
    auto& self = *static_cast<Daemon*>(userdata);
    if (info->ssi_signo == SIGHUP) {
      try {
        self.reloads_.request(nullptr);        // its outcome is logged
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
      self.stop_loop(1);
    }
    sd_event_source_set_time_relative(source, kTickUsec);
    sd_event_source_set_enabled(source, SD_EVENT_ON);
    return 0;
  }

  void tick() {
    run_requested_test_fault();
    const Nanos now = backends_.clock->now();
    const double t = seconds(now - start_time_);
    world_->step(t);
    const PressureStatus pressure = sprayer_->pressure();
    const ControlStatus control = sprayer_->control();
    loops_.report_stalls(*sprayer_, pressure);
    operation_.finish_starting(pressure, control, previous_run_unfinished_);
    operation_.follow_key();
    loops_.drain_latencies(*sprayer_);
    live_view_->poll(now);
    operation_.update_calibration();
    reloads_.finish();
    alarms_.evaluate(now, pressure, control,
                     {config_, backends_, *sprayer_, *world_, operation_, loops_, outputs_,
                      exit_watch_, *records_, dbus_.get()});
    loops_.feed_watchdog(*sprayer_, now, pressure, control);
    if (t - last_status_s_ >= 1.0 / config_.daemon.status_max_rate_hz) {
      last_status_s_ = t;
      const Status status = make_status(pressure, control);
      if (dbus_) dbus_->update(status);
      world_->status_published(status, t);
    }
    if (options_.run_seconds > 0 && t >= options_.run_seconds) sd_event_exit(event_, 0);
  }

  Status make_status(const PressureStatus& pressure, const ControlStatus& control) const {
    return build_status(
        {config_, backends_, *sprayer_, operation_.state(), operation_.setpoint_mpa(),
         operation_.decision_threshold(), operation_.nominal_flow_l_per_min(), alarms_.alarms(),
         records_->totals(), loops_.latency_p99(),
         LoopHealth::total_overruns(*sprayer_, pressure, control), operation_.calibrations()},
        pressure, control);
  }

  // Commands show their effect on the bus at once, not at the next status period.
  void refresh_status() {
    if (dbus_ && sprayer_) dbus_->update(make_status(sprayer_->pressure(), sprayer_->control()));
  }

  Options options_;
  Config config_;
  Backends backends_;
  std::unique_ptr<WorldDriver> world_;  // around backends_ (nothing to drive on the board)
  std::unique_ptr<Sprayer> sprayer_;
  std::unique_ptr<LiveView> live_view_;  // main thread; before sprayer_ in destruction
  Operation operation_;
  AlarmWatch alarms_;
  LoopHealth loops_;
  OutputChecks outputs_;
  std::optional<RunMarker> run_marker_;  // present once the state folder is set up
  std::optional<RunRecords> records_;    // from run() on; its writer drains sprayer_'s records
  ConfigReloads reloads_;
  std::optional<Commands> commands_;   // from run() on
  std::unique_ptr<DbusService> dbus_;  // calls commands_
  sd_event* event_ = nullptr;
  sd_event_source* tick_source_ = nullptr;
  std::vector<sd_event_source*> signal_sources_;
  Nanos start_time_{};
  bool previous_run_unfinished_ = false;
  double last_status_s_ = -1e9;
  int exit_code_ = 0;
  ExitWatch exit_watch_;
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
  lock_what_the_loops_run();

  std::optional<ExitWatch> exit_watch = ExitWatch::arm(run.config, options);
  if (!exit_watch) return 1;
  Daemon daemon(options, std::move(run.config), std::move(*exit_watch));
  try {
    return daemon.run();
  } catch (const std::exception& error) {
    spdlog::critical("fatal: {}", error.what());
    daemon.shutdown();
    return 1;
  }
}

}  // namespace weedspray::daemon
