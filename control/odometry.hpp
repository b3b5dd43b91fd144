// SPDX-License-Identifier: Apache-2.0
// Wheel odometry from a Hall sensor (SPEC §4/§5): distance and speed from a free-running pulse
// counter and the kernel timestamp of the counter's last edge.
// - Distance = accumulated pulses / pulses_per_metre; the counter may wrap (counter_bits wide):
//   increments are taken modulo 2^counter_bits.
// - Speed = pulses / time between edge timestamps, over at least speed_window (so 1-pulse
//   quantisation does not dominate at high pulse rates).
// - Standing still: with no new pulse the speed is capped by "one pulse distance / time since
//   the last edge" (it can only be slower than that), and is 0 after standstill_timeout.
// - distance_at(t): interpolated from a fixed ring of recent (edge time, distance) samples, so
//   a camera frame's timestamp (in the past) maps to the odometer reading at that instant;
//   beyond the last edge it extrapolates with the current speed, never past the next pulse.
// Timestamps: std::chrono::nanoseconds, CLOCK_MONOTONIC. Pure; update() allocation-free.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>

namespace weedspray::control {

struct OdometryConfig {
  double pulses_per_metre = 100.0;
  std::chrono::nanoseconds speed_window{std::chrono::milliseconds(50)};
  std::chrono::nanoseconds standstill_timeout{std::chrono::milliseconds(1000)};
  unsigned counter_bits = 32;  // 1..64
};

class Odometry {
 public:
  // Throws std::invalid_argument naming the field.
  explicit Odometry(const OdometryConfig& config);

  // Feed the counter value, the timestamp of the counter's last edge, and the current time.
  // The first call only sets the reference (distance 0).
  void update(std::uint64_t pulse_count, std::chrono::nanoseconds last_edge_time,
              std::chrono::nanoseconds now) noexcept;

  double distance_m() const noexcept { return distance_m_; }
  double speed_m_per_s() const noexcept { return speed_m_per_s_; }
  std::uint64_t total_pulses() const noexcept { return total_pulses_; }
  // Odometer reading at time t (see header comment).
  double distance_at(std::chrono::nanoseconds t) const noexcept;
  void reset() noexcept;

 private:
  struct Sample {
    std::chrono::nanoseconds time{0};
    double distance_m = 0.0;
  };
  static constexpr std::size_t kHistory = 256;

  OdometryConfig config_;
  std::uint64_t counter_mask_;
  bool initialised_ = false;
  std::uint64_t last_count_ = 0;
  std::chrono::nanoseconds last_edge_time_{0};
  std::uint64_t total_pulses_ = 0;
  double distance_m_ = 0.0;
  double measured_speed_m_per_s_ = 0.0;  // from the last speed window
  double speed_m_per_s_ = 0.0;           // after the standstill cap
  std::uint64_t window_start_pulses_ = 0;
  std::chrono::nanoseconds window_start_time_{0};
  bool window_valid_ = false;  // false after a standstill: the next edge opens a new window
  std::array<Sample, kHistory> history_{};
  std::size_t history_size_ = 0;
  std::size_t history_head_ = 0;  // next write slot
};

}  // namespace weedspray::control
