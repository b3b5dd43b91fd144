// SPDX-License-Identifier: Apache-2.0
// The valve PWM driver: the highest-priority RT loop. It executes a stream of PWM edges (from
// control's staggered PwmSchedule) on an output bank: sleep until the edge on the injected
// clock, write the whole valve mask with one call. Duty commands arrive wait-free through a
// LatestValue slot; a DEAD-MAN rule closes every valve (force_safe) when commands are not
// refreshed within `command_expiry`, and keeps them closed until a fresh command arrives.
//
// The schedule is control::PwmSchedule (control/pwm_schedule.hpp); it is a template parameter
// only so tests can substitute a scripted one. The driver uses:
//   void start(std::chrono::nanoseconds t0) noexcept;   // restart phases at t0
//   void set_duties(std::span<const double> duty_pct, std::chrono::nanoseconds now) noexcept;
//   std::uint32_t force_closed() noexcept;              // all duties -> 0
//   PwmEdge peek_edge() const noexcept;                 // next edge, without advancing
//   PwmEdge next_edge() noexcept;                       // .time, .valve_mask (all valves)
// The driver never holds a fetched edge across a sleep: it peeks the next edge on every wake,
// so new duties (an immediate spray start/stop in the schedule) apply at once, not one edge
// late.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <span>
#include <stop_token>
#include <utility>

#include "io/clock.hpp"
#include "io/digital_output.hpp"
#include "io/lateness_histogram.hpp"
#include "io/latest_value.hpp"

namespace weedspray::io {

inline constexpr std::size_t kMaxValves = 32;

struct ValveCommand {
  std::array<double, kMaxValves> duty_pct{};  // per valve, 0..100
  std::uint32_t valve_count = 0;
  std::chrono::nanoseconds issued_at{};  // producer's clock time; the dead-man measures from it
};

struct ValvePwmDriverConfig {
  // Commands older than this close all valves (dead-man).
  std::chrono::nanoseconds command_expiry = std::chrono::milliseconds(500);
  // Longest sleep between checks of stop requests, new commands and expiry.
  std::chrono::nanoseconds max_sleep = std::chrono::milliseconds(20);
  // An edge written later than this after its time counts as late.
  std::chrono::nanoseconds late_threshold = std::chrono::microseconds(500);
  // An edge later than this misplaces the spray (the daemon's control_overruns alarm counts
  // these while spraying): 5 ms is 12.5 mm of travel at 2.5 m/s, 2.5 % of a 5 Hz period.
  std::chrono::nanoseconds miss_tolerance = std::chrono::milliseconds(5);
  // Every edge's lateness, if set (owned by the caller so other threads can summarise it).
  LatenessHistogram* lateness = nullptr;
  // Called on every wake of this, the highest-priority thread (e.g. to watch other loops);
  // must be real-time safe. A plain function pointer: nothing to allocate or copy.
  void (*on_wake)(void* context, std::chrono::nanoseconds now) noexcept = nullptr;
  void* on_wake_context = nullptr;
  // Heartbeat output (LinuxCNC's charge pump): toggled every half period while this loop runs,
  // left at its safe (low) value when it returns, when a valve bank write fails, and while
  // stop_heartbeat() holds. An external retriggerable relay powers the valves (and the pump)
  // only while the wave comes, so a stopped real-time core or a Fault cuts them in hardware.
  DigitalOutputBank* heartbeat = nullptr;
  std::chrono::nanoseconds heartbeat_half_period = std::chrono::milliseconds(10);
  // While *hold_safe is true (a latched emergency stop) the valves stay closed and the
  // heartbeat low. Checked at every wake, and so also straight after every valve write (the
  // loop goes round without sleeping): a write that raced the flag's setter, which writes the
  // valves safe itself, is undone before this thread sleeps.
  const std::atomic<bool>* hold_safe = nullptr;
  // While *hold_closed is true (the pressure loop's fault reaction: a sensor fault, stale
  // samples, an over-pressure trip) the valves stay closed, checked like hold_safe; the
  // heartbeat goes on, so the valves open again when the fault clears.
  const std::atomic<bool>* hold_closed = nullptr;
};

struct ValvePwmStats {
  std::uint64_t wakes = 0;  // loop iterations: advances at least every max_sleep while alive
  std::uint64_t heartbeat_toggles = 0;
  bool heartbeat_stopped = false;  // held low: stop_heartbeat() or a failed valve write
  std::uint64_t edges_written = 0;
  std::uint64_t late_edges = 0;              // written > late_threshold after their time
  std::uint64_t missed_edges = 0;            // written > miss_tolerance after their time
  std::uint64_t skipped_edges = 0;           // already a whole edge behind: state applied at once
  std::uint64_t write_errors = 0;            // valve bank writes refused (safe writes included)
  std::uint64_t heartbeat_write_errors = 0;  // heartbeat output writes refused
  std::uint64_t commands_applied = 0;
  std::uint64_t deadman_expiries = 0;
  std::uint64_t holds = 0;  // times hold_safe or hold_closed closed the valves
  std::chrono::nanoseconds max_lateness{0};
  std::uint32_t last_mask = 0;
  std::chrono::nanoseconds last_mask_written_at{0};  // clock time just after the write
  std::chrono::nanoseconds schedule_start{0};        // t0 of the schedule's current run
  bool expired = true;                               // valves held closed: no fresh command
};

template <class Schedule>
class ValvePwmDriver {
 public:
  ValvePwmDriver(Clock& clock, DigitalOutputBank& bank, Schedule& schedule,
                 ValvePwmDriverConfig config) noexcept
      : clock_(clock), bank_(bank), schedule_(schedule), config_(config) {}

  // Producer side (any one thread): a fresh command also refreshes the dead-man.
  void command(const ValveCommand& cmd) noexcept { commands_.publish(cmd); }

  // Any thread, wait-free: the heartbeat goes low at this loop's next wake and stays low until
  // resume_heartbeat() (a latched Fault, a refused output write). A failed write of the valve
  // bank stops it from inside the loop, the same way.
  void stop_heartbeat() noexcept { heartbeat_stopped_.store(true); }
  void resume_heartbeat() noexcept { heartbeat_stopped_.store(false); }

  // Counters, readable from any thread.
  ValvePwmStats stats() const noexcept { return published_stats_.read(); }
  // For real-time readers: false (out unchanged) when the slot was busy.
  bool try_stats(ValvePwmStats& out) const noexcept { return published_stats_.try_read(out); }

  // The RT loop. Starts with the valves safe; returns with the valves safe.
  void run(std::stop_token stop) noexcept {
    bank_.force_safe();
    stats_.last_mask = bank_.safe_mask();
    std::uint64_t seen_version = 0;
    std::chrono::nanoseconds refreshed_at{};
    bool have_command = false;

    while (!stop.stop_requested()) {
      ++stats_.wakes;
      std::chrono::nanoseconds now = clock_.now();
      if (config_.on_wake != nullptr) config_.on_wake(config_.on_wake_context, now);
      beat(now);
      const std::uint64_t version = commands_.version();
      if (version != seen_version) {
        ValveCommand cmd;
        if (commands_.try_read(cmd)) {
          seen_version = version;
          const std::uint32_t n = std::min<std::uint32_t>(
              cmd.valve_count, static_cast<std::uint32_t>(std::min(bank_.size(), kMaxValves)));
          schedule_.set_duties(std::span<const double>(cmd.duty_pct.data(), n), now);
          refreshed_at = cmd.issued_at;
          have_command = true;
          ++stats_.commands_applied;
        }
      }

      const std::chrono::nanoseconds expires_at = refreshed_at + config_.command_expiry;
      const bool held = held_safe() || held_closed();
      if (held || !have_command || now >= expires_at) {
        if (held && !holding_) ++stats_.holds;
        holding_ = held;
        if (!stats_.expired) {
          schedule_.force_closed();
          if (bank_.force_safe() != 0) count_write_error();
          stats_.last_mask = bank_.safe_mask();
          stats_.expired = true;
          if (!held) ++stats_.deadman_expiries;
        }
        publish_stats();
        clock_.sleep_until(std::min(now + config_.max_sleep, next_beat_));
        continue;
      }
      holding_ = false;
      if (stats_.expired) {
        // Fresh commands after start-up or an expiry: restart the staggered phases now.
        stats_.expired = false;
        schedule_.start(now);
        stats_.schedule_start = now;
      }

      // Peeked afresh on every wake, so duties set since the last wake are reflected.
      const PwmEdgeT upcoming = schedule_.peek_edge();
      const std::chrono::nanoseconds wake =
          std::min({upcoming.time, expires_at, now + config_.max_sleep, next_beat_});
      if (wake > now) {
        publish_stats();  // wakes advance even when no edge is due (the watchdog reads them)
        clock_.sleep_until(wake);
        continue;  // re-check stop, commands and expiry before the edge
      }

      // The edge is due. Behind by more than one edge (e.g. a late wake): skip to the latest due
      // edge, which carries the current state of every valve.
      PwmEdgeT edge = schedule_.next_edge();
      for (int guard = 0; guard < kMaxSkip && schedule_.peek_edge().time <= now; ++guard) {
        ++stats_.skipped_edges;
        edge = schedule_.next_edge();
      }
      write_mask(edge.valve_mask);
      now = clock_.now();
      stats_.last_mask_written_at = now;
      const std::chrono::nanoseconds lateness = now - edge.time;
      if (lateness > stats_.max_lateness) stats_.max_lateness = lateness;
      if (lateness > config_.late_threshold) ++stats_.late_edges;
      if (lateness > config_.miss_tolerance) ++stats_.missed_edges;
      if (config_.lateness != nullptr) config_.lateness->record(lateness);
      ++stats_.edges_written;
      publish_stats();
    }
    if (bank_.force_safe() != 0) ++stats_.write_errors;
    stats_.last_mask = bank_.safe_mask();
    stats_.expired = true;
    if (config_.heartbeat != nullptr && config_.heartbeat->force_safe() != 0)
      ++stats_.heartbeat_write_errors;
    publish_stats();
  }

 private:
  using PwmEdgeT = decltype(std::declval<Schedule&>().next_edge());
  static constexpr int kMaxSkip = 100000;

  void write_mask(std::uint32_t mask) noexcept {
    if (bank_.write(mask) != 0) count_write_error();
    stats_.last_mask = mask;
  }
  bool held_safe() const noexcept {
    return config_.hold_safe != nullptr && config_.hold_safe->load();
  }
  bool held_closed() const noexcept {
    return config_.hold_closed != nullptr && config_.hold_closed->load();
  }
  // A valve may be stuck open: the relay must cut the valves' power.
  void count_write_error() noexcept {
    ++stats_.write_errors;
    heartbeat_stopped_.store(true);
  }
  void publish_stats() noexcept { published_stats_.publish(stats_); }

  void beat(std::chrono::nanoseconds now) noexcept {
    if (config_.heartbeat == nullptr) {
      next_beat_ = std::chrono::nanoseconds::max();
      return;
    }
    if (heartbeat_stopped_.load() || held_safe()) {
      if (!stats_.heartbeat_stopped) {
        stats_.heartbeat_stopped = true;
        beat_level_ = false;
        next_beat_ = std::chrono::nanoseconds::max();
        if (config_.heartbeat->force_safe() != 0) ++stats_.heartbeat_write_errors;
      }
      return;
    }
    stats_.heartbeat_stopped = false;
    if (now < next_beat_ && next_beat_ != std::chrono::nanoseconds::max()) return;
    beat_level_ = !beat_level_;
    if (config_.heartbeat->write(beat_level_ ? 1U : 0U) != 0) ++stats_.heartbeat_write_errors;
    ++stats_.heartbeat_toggles;
    next_beat_ = now + config_.heartbeat_half_period;
  }

  Clock& clock_;
  DigitalOutputBank& bank_;
  Schedule& schedule_;
  ValvePwmDriverConfig config_;
  LatestValue<ValveCommand> commands_;
  LatestValue<ValvePwmStats> published_stats_;
  ValvePwmStats stats_;
  std::chrono::nanoseconds next_beat_ = std::chrono::nanoseconds::max();
  bool beat_level_ = false;
  bool holding_ = false;
  std::atomic<bool> heartbeat_stopped_{false};
};

}  // namespace weedspray::io
