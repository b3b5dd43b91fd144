// SPDX-License-Identifier: Apache-2.0
// How the real-time loops keep time, watched from the main thread: the vision latency window,
// the deadline misses while spraying, the stalls the loops' cross-watch acted on, the systemd
// watchdog (fed only while the loops make progress), the CPU wake-up latency request, and the
// timing report at exit.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "daemon/sprayer/sprayer.hpp"
#include "daemon/supervision/loop_timing.hpp"
#include "io/linux/cpu_latency_qos.hpp"

namespace weedspray::daemon {

class LoopHealth {
 public:
  // A PM QoS request keeps the CPUs out of slow idle states while the loops run (see
  // io/linux/cpu_latency_qos.hpp for what it fixes); us < 0: none.
  void request_cpu_wakeup_latency(int us);
  void release_cpu_wakeup_latency() { cpu_latency_ = {}; }
  // From the loops' start: the run's time base, and the watchdog when systemd set one.
  void start(Nanos now);

  // Each tick.
  void drain_latencies(Sprayer& sprayer);
  void report_stalls(const Sprayer& sprayer, const PressureStatus& pressure);
  // Counts the misses while spraying and the overruns of the last whole second.
  void count_misses(const Sprayer& sprayer, Nanos now, bool spraying,
                    const PressureStatus& pressure, const ControlStatus& control);
  void feed_watchdog(const Sprayer& sprayer, Nanos now, const PressureStatus& pressure,
                     const ControlStatus& control);

  double latency_p99() const;
  std::uint64_t overruns_last_second() const noexcept { return overruns_last_second_; }
  // Every loop's overruns (the ControlOverruns property).
  static std::uint64_t total_overruns(const Sprayer& sprayer, const PressureStatus& pressure,
                                      const ControlStatus& control);
  std::string report_line(const Sprayer& sprayer, Nanos now, const PressureStatus& pressure,
                          const ControlStatus& control) const;
  // At exit: the journal line, and the JSON report to `path` ("-": stdout; "": none).
  void report_timing(const Sprayer& sprayer, Nanos now, const std::string& path) const noexcept;

 private:
  TimingReportInput timing_input(const Sprayer& sprayer, Nanos now, const PressureStatus& pressure,
                                 const ControlStatus& control) const;

  Nanos start_time_{};
  std::vector<float> latencies_;
  std::size_t latency_next_ = 0;
  Nanos last_tick_time_{};
  Nanos overrun_window_start_{};
  std::uint64_t overruns_at_window_start_ = 0;
  std::uint64_t overruns_last_second_ = 0;
  std::uint64_t misses_seen_ = 0;
  std::uint64_t misses_while_spraying_ = 0;
  double spraying_seconds_ = 0;
  std::uint64_t pressure_stalls_seen_ = 0;
  std::uint64_t valve_stalls_seen_ = 0;
  Nanos watchdog_interval_{0};
  Nanos last_watchdog_{};
  std::uint64_t heartbeat_pressure_ = 0;
  std::uint64_t heartbeat_control_ = 0;
  std::uint64_t heartbeat_valves_ = 0;
  io::hw::CpuLatencyRequest cpu_latency_;
  std::string cpu_latency_state_ = "none";
};

}  // namespace weedspray::daemon
