// SPDX-License-Identifier: Apache-2.0
// Real-time threads: ALL thread priorities in one table, SCHED_FIFO when permitted (normal
// priority plus a returned status otherwise, so an unprivileged run still works), and
// a periodic loop on absolute deadlines of the injected clock with an overrun counter.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <stop_token>
#include <string>
#include <string_view>
#include <thread>

#include "io/clock.hpp"
#include "io/lateness_histogram.hpp"

namespace weedspray::io {

enum class ThreadRole {
  kEstop,         // the emergency-stop input: its reaction writes valves and pump safe
  kValvePwm,      // valve edges: the tightest deadline in the system
  kPulseInput,    // flow meter / wheel edge readers
  kAnalogIo,      // the pressure converters' blocking I/O (IIO on I2C, Modbus modules)
  kPressureLoop,  // ADC sample -> fuzzy PID -> DAC command
  kControl,       // spray-rate law and distance scheduling
  kDigitalInput,  // start/stop key
  kCamera,        // capture + vision (normal priority)
  kModbus,        // tank level (normal priority; blocking reads)
  kGnss,          // the gpsd client (normal priority; blocking reads)
  kImu,           // the yaw-rate gyro's sysfs reads (normal priority; may wait on I2C)
};

struct ThreadPriority {
  ThreadRole role;
  std::string_view name;  // thread name (max 15 chars, shown by ps/top)
  int fifo_priority;      // SCHED_FIFO priority 1..99; 0 = normal (SCHED_OTHER)
};

// The one table. The loops sit above the kernel's threaded IRQ handlers (50) so device
// interrupts cannot delay a deadline; each only runs briefly and then sleeps (a blocked read,
// e.g. an I2C conversion, sleeps too, so the IRQ thread that completes it still runs).
inline constexpr std::array<ThreadPriority, 11> kThreadPriorities{{
    {ThreadRole::kEstop, "ws-estop", 85},
    {ThreadRole::kValvePwm, "ws-valve-pwm", 80},
    {ThreadRole::kPulseInput, "ws-pulses", 70},
    {ThreadRole::kAnalogIo, "ws-analog", 65},
    {ThreadRole::kPressureLoop, "ws-pressure", 60},
    {ThreadRole::kControl, "ws-control", 40},
    {ThreadRole::kDigitalInput, "ws-key", 30},
    {ThreadRole::kCamera, "ws-camera", 0},
    {ThreadRole::kModbus, "ws-modbus", 0},
    {ThreadRole::kGnss, "ws-gnss", 0},
    {ThreadRole::kImu, "ws-imu", 0},
}};

constexpr const ThreadPriority& thread_priority(ThreadRole role) noexcept {
  for (const auto& p : kThreadPriorities)
    if (p.role == role) return p;
  return kThreadPriorities.back();
}

enum class RtStatus {
  kRealtime,        // running SCHED_FIFO at the table's priority
  kNormalPriority,  // the table asks for normal priority
  kNoPermission,    // SCHED_FIFO refused (no CAP_SYS_NICE / RLIMIT_RTPRIO): running normally
  kFailed,          // another error setting the policy: running normally
};

std::string_view to_string(RtStatus status) noexcept;

// Applies the table's policy and name to the calling thread.
RtStatus apply_thread_role(ThreadRole role) noexcept;

// A std::jthread running `body(stop_token)` with the role's policy applied first. The
// constructor waits until the thread has applied its policy, so status() is final.
class RealtimeThread {
 public:
  RealtimeThread() = default;
  RealtimeThread(ThreadRole role, std::function<void(std::stop_token)> body);
  RealtimeThread(RealtimeThread&&) noexcept = default;
  RealtimeThread& operator=(RealtimeThread&&) noexcept = default;
  ~RealtimeThread() { stop_and_join(); }

  RtStatus status() const noexcept { return status_; }
  bool joinable() const noexcept { return thread_.joinable(); }
  void request_stop() noexcept { thread_.request_stop(); }
  void stop_and_join() noexcept;

 private:
  std::jthread thread_;
  RtStatus status_ = RtStatus::kFailed;
};

// Periodic loop on absolute deadlines: deadline k = start + k * period. A wake-up later than
// the next deadline counts as an overrun and skips the missed deadlines (no burst catch-up).
// Every wake's lateness goes into an optional histogram (owned by the caller, so other threads
// can read it), and a wake later than `miss_tolerance` counts as a miss: the figure the daemon's
// control_overruns alarm is built on (a lateness that affects spraying, not any late wake).
class PeriodicLoop {
 public:
  PeriodicLoop(Clock& clock, std::chrono::nanoseconds period, std::chrono::nanoseconds start,
               LatenessHistogram* lateness = nullptr,
               std::chrono::nanoseconds miss_tolerance = std::chrono::nanoseconds::max()) noexcept
      : clock_(clock),
        period_(period),
        next_(start),
        lateness_(lateness),
        miss_tolerance_(miss_tolerance) {}

  // Sleeps until the next deadline; returns the deadline that was due.
  std::chrono::nanoseconds wait_next() noexcept {
    clock_.sleep_until(next_);
    const std::chrono::nanoseconds due = next_;
    const std::chrono::nanoseconds now = clock_.now();
    const std::chrono::nanoseconds late = now - due;
    if (late > max_lateness_) max_lateness_ = late;
    if (lateness_ != nullptr) lateness_->record(late);
    if (late > miss_tolerance_) ++misses_;
    next_ += period_;
    if (now >= next_) {
      const auto missed = (now - next_) / period_ + 1;
      overruns_ += static_cast<std::uint64_t>(missed);
      next_ += missed * period_;
    }
    ++cycles_;
    return due;
  }

  std::uint64_t cycles() const noexcept { return cycles_; }
  std::uint64_t overruns() const noexcept { return overruns_; }
  std::uint64_t misses() const noexcept { return misses_; }
  std::chrono::nanoseconds max_lateness() const noexcept { return max_lateness_; }
  std::chrono::nanoseconds period() const noexcept { return period_; }

 private:
  Clock& clock_;
  std::chrono::nanoseconds period_;
  std::chrono::nanoseconds next_;
  LatenessHistogram* lateness_;
  std::chrono::nanoseconds miss_tolerance_;
  std::uint64_t cycles_ = 0;
  std::uint64_t overruns_ = 0;
  std::uint64_t misses_ = 0;
  std::chrono::nanoseconds max_lateness_{0};
};

}  // namespace weedspray::io
