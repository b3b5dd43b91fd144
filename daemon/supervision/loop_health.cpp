// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/loop_health.hpp"

#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <algorithm>
#include <cstdio>
#include <fstream>

namespace weedspray::daemon {
namespace {

constexpr std::size_t kLatencyWindow = 1000;

double seconds(Nanos t) {
  return std::chrono::duration<double>(t).count();
}

// Lateness that affects spraying (alarms.timing_tolerance_ms), in any loop.
std::uint64_t total_misses(const Sprayer& sprayer, const PressureStatus& pressure,
                           const ControlStatus& control) {
  return pressure.misses + control.misses + sprayer.pwm().missed_edges;
}

}  // namespace

void LoopHealth::request_cpu_wakeup_latency(int us) {
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

void LoopHealth::start(Nanos now) {
  start_time_ = now;
  last_tick_time_ = now;
  uint64_t watchdog_usec = 0;
  if (sd_watchdog_enabled(0, &watchdog_usec) > 0)
    watchdog_interval_ = Nanos(watchdog_usec * 1000 / 2);
}

void LoopHealth::drain_latencies(Sprayer& sprayer) {
  while (auto latency = sprayer.latencies().try_pop()) {
    if (latencies_.size() < kLatencyWindow) {
      latencies_.push_back(*latency);
    } else {
      latencies_[latency_next_] = *latency;
    }
    latency_next_ = (latency_next_ + 1) % kLatencyWindow;
  }
}

double LoopHealth::latency_p99() const {
  if (latencies_.empty()) return 0;
  std::vector<float> sorted = latencies_;
  const auto k = static_cast<std::size_t>(0.99 * static_cast<double>(sorted.size() - 1));
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(k), sorted.end());
  return sorted[k];
}

// The loops' cross-watch acted: say so (the late wakes also count as misses).
void LoopHealth::report_stalls(const Sprayer& sprayer, const PressureStatus& pressure) {
  const std::uint64_t pressure_stalls = sprayer.pressure_loop_stalls();
  if (pressure_stalls != pressure_stalls_seen_) {
    spdlog::error("pressure loop stalled with the pump on: the valve thread switched it off");
    pressure_stalls_seen_ = pressure_stalls;
  }
  if (pressure.valve_thread_stalls != valve_stalls_seen_) {
    spdlog::error("valve thread stalled: pump off and return valve open until it runs again");
    valve_stalls_seen_ = pressure.valve_thread_stalls;
  }
}

// Only misses while spraying count: a late wake in Idle moves no liquid.
void LoopHealth::count_misses(const Sprayer& sprayer, Nanos now, bool spraying,
                              const PressureStatus& pressure, const ControlStatus& control) {
  const std::uint64_t misses = total_misses(sprayer, pressure, control);
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
}

// The watchdog is fed only while the real-time loops make progress.
void LoopHealth::feed_watchdog(const Sprayer& sprayer, Nanos now, const PressureStatus& pressure,
                               const ControlStatus& control) {
  if (watchdog_interval_.count() == 0 || now - last_watchdog_ < watchdog_interval_) return;
  const std::uint64_t valve_wakes = sprayer.pwm().wakes;
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

std::uint64_t LoopHealth::total_overruns(const Sprayer& sprayer, const PressureStatus& pressure,
                                         const ControlStatus& control) {
  return pressure.overruns + control.overruns + sprayer.pwm().late_edges +
         sprayer.analog_io().overruns;
}

TimingReportInput LoopHealth::timing_input(const Sprayer& sprayer, Nanos now,
                                           const PressureStatus& pressure,
                                           const ControlStatus& control) const {
  TimingReportInput in;
  in.timing = &sprayer.timing();
  const io::ValvePwmStats pwm = sprayer.pwm();
  in.valve_edges = {pwm.skipped_edges, pwm.missed_edges};
  in.pressure_loop = {pressure.overruns, pressure.misses};
  in.control_loop = {control.overruns, control.misses};
  in.converter_overruns = sprayer.analog_io().overruns;
  in.misses_while_spraying = misses_while_spraying_;
  in.seconds = seconds(now - start_time_);
  in.spraying_seconds = spraying_seconds_;
  in.realtime = sprayer.realtime_warnings().empty();
  in.cpu_latency_request = cpu_latency_state_;
  return in;
}

std::string LoopHealth::report_line(const Sprayer& sprayer, Nanos now,
                                    const PressureStatus& pressure,
                                    const ControlStatus& control) const {
  return timing_report_line(timing_input(sprayer, now, pressure, control));
}

void LoopHealth::report_timing(const Sprayer& sprayer, Nanos now,
                               const std::string& path) const noexcept {
  try {
    const TimingReportInput in = timing_input(sprayer, now, sprayer.pressure(), sprayer.control());
    spdlog::info("real-time timing: {}", timing_report_line(in));
    if (path.empty()) return;
    const std::string json = timing_report_json(in);
    if (path == "-") {
      std::printf("%s\n", json.c_str());
      std::fflush(stdout);
    } else if (!(std::ofstream(path) << json << '\n')) {
      spdlog::error("timing report: cannot write {}", path);
    }
  } catch (const std::exception& error) {
    spdlog::error("timing report: {}", error.what());
  }
}

}  // namespace weedspray::daemon
