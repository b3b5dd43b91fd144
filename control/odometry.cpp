// SPDX-License-Identifier: Apache-2.0
#include "control/odometry.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace weedspray::control {

using std::chrono::nanoseconds;

namespace {
double seconds(nanoseconds d) {
  return static_cast<double>(d.count()) * 1e-9;
}
}  // namespace

Odometry::Odometry(const OdometryConfig& config) : config_(config), counter_mask_(0) {
  if (!std::isfinite(config.pulses_per_metre) || config.pulses_per_metre <= 0.0) {
    throw std::invalid_argument("OdometryConfig.pulses_per_metre must be > 0");
  }
  if (config.speed_window.count() < 0) {
    throw std::invalid_argument("OdometryConfig.speed_window must be >= 0");
  }
  if (config.standstill_timeout.count() <= 0) {
    throw std::invalid_argument("OdometryConfig.standstill_timeout must be > 0");
  }
  if (config.counter_bits < 1 || config.counter_bits > 64) {
    throw std::invalid_argument("OdometryConfig.counter_bits must be 1..64, got " +
                                std::to_string(config.counter_bits));
  }
  counter_mask_ =
      config.counter_bits == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << config.counter_bits) - 1;
}

void Odometry::reset() noexcept {
  initialised_ = false;
  total_pulses_ = 0;
  distance_m_ = 0.0;
  measured_speed_m_per_s_ = 0.0;
  speed_m_per_s_ = 0.0;
  history_size_ = 0;
  history_head_ = 0;
}

void Odometry::update(std::uint64_t pulse_count, nanoseconds last_edge_time,
                      nanoseconds now) noexcept {
  pulse_count &= counter_mask_;
  if (!initialised_) {
    initialised_ = true;
    last_count_ = pulse_count;
    last_edge_time_ = last_edge_time;
    window_start_pulses_ = 0;
    window_start_time_ = last_edge_time;
    window_valid_ = true;
    history_[0] = Sample{last_edge_time, 0.0};
    history_size_ = 1;
    history_head_ = 1 % kHistory;
    return;
  }
  // Unsigned subtraction modulo 2^bits: a wrapped counter still gives the right increment.
  const std::uint64_t delta = (pulse_count - last_count_) & counter_mask_;
  last_count_ = pulse_count;
  if (delta > 0 && last_edge_time > last_edge_time_) {
    total_pulses_ += delta;
    distance_m_ = static_cast<double>(total_pulses_) / config_.pulses_per_metre;
    last_edge_time_ = last_edge_time;
    history_[history_head_] = Sample{last_edge_time, distance_m_};
    history_head_ = (history_head_ + 1) % kHistory;
    history_size_ = std::min(history_size_ + 1, kHistory);
    const nanoseconds window = last_edge_time - window_start_time_;
    if (!window_valid_) {
      window_valid_ = true;
      window_start_pulses_ = total_pulses_;
      window_start_time_ = last_edge_time;
    } else if (window >= config_.speed_window && window.count() > 0) {
      measured_speed_m_per_s_ = static_cast<double>(total_pulses_ - window_start_pulses_) /
                                config_.pulses_per_metre / seconds(window);
      window_start_pulses_ = total_pulses_;
      window_start_time_ = last_edge_time;
    }
  } else if (delta > 0) {
    // Count moved but the edge time did not: keep the distance, no speed information.
    total_pulses_ += delta;
    distance_m_ = static_cast<double>(total_pulses_) / config_.pulses_per_metre;
  }
  const nanoseconds since_edge = now - last_edge_time_;
  if (since_edge >= config_.standstill_timeout) {
    measured_speed_m_per_s_ = 0.0;
    speed_m_per_s_ = 0.0;
    // A restart measures from its first edge, not across the standstill.
    window_valid_ = false;
    return;
  }
  double speed = measured_speed_m_per_s_;
  if (since_edge.count() > 0) {
    // No pulse for since_edge: the vehicle cannot be faster than one pulse in that time.
    speed = std::min(speed, 1.0 / config_.pulses_per_metre / seconds(since_edge));
  }
  speed_m_per_s_ = speed;
}

double Odometry::distance_at(nanoseconds t) const noexcept {
  if (history_size_ == 0) return 0.0;
  auto at = [this](std::size_t age) -> const Sample& {  // age 0 = newest
    return history_[(history_head_ + kHistory - 1 - age) % kHistory];
  };
  const Sample& newest = at(0);
  if (t >= newest.time) {
    const double ahead = speed_m_per_s_ * seconds(t - newest.time);
    return newest.distance_m + std::min(ahead, 1.0 / config_.pulses_per_metre);
  }
  for (std::size_t age = 1; age < history_size_; ++age) {
    const Sample& older = at(age);
    if (t >= older.time) {
      const Sample& newer = at(age - 1);
      const double f = seconds(t - older.time) / seconds(newer.time - older.time);
      return older.distance_m + f * (newer.distance_m - older.distance_m);
    }
  }
  return at(history_size_ - 1).distance_m;
}

}  // namespace weedspray::control
