// SPDX-License-Identifier: Apache-2.0
#include "control/odometry.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>

namespace weedspray::control {
namespace {

using namespace std::chrono_literals;
using std::chrono::nanoseconds;

OdometryConfig config_100ppm() {
  OdometryConfig config;
  config.pulses_per_metre = 100.0;
  config.speed_window = 50ms;
  config.standstill_timeout = 1s;
  return config;
}

// Feeds a counter that advances one pulse every `pulse_period`, polled every `poll`.
struct Wheel {
  Odometry odometry;
  std::uint64_t count;
  nanoseconds last_edge;
  void run(nanoseconds from, nanoseconds to, nanoseconds pulse_period, nanoseconds poll) {
    nanoseconds next_pulse = from + pulse_period;
    for (nanoseconds now = from; now <= to; now += poll) {
      while (next_pulse <= now) {
        ++count;
        last_edge = next_pulse;
        next_pulse += pulse_period;
      }
      odometry.update(count, last_edge, now);
    }
  }
};

TEST(Odometry, ConstantSpeed) {
  Wheel wheel{Odometry(config_100ppm()), 0, 0ns};
  wheel.run(0ns, 1s, 10ms, 1ms);  // 100 pulses per second at 100 /m = 1 m/s
  EXPECT_NEAR(wheel.odometry.distance_m(), 1.0, 1e-9);
  EXPECT_NEAR(wheel.odometry.speed_m_per_s(), 1.0, 1e-9);
  EXPECT_EQ(wheel.odometry.total_pulses(), 100u);
}

TEST(Odometry, CounterWrap) {
  OdometryConfig config = config_100ppm();
  config.counter_bits = 16;
  Wheel wheel{Odometry(config), 65500, 0ns};
  wheel.run(0ns, 2s, 5ms, 1ms);  // 400 pulses, wrapping past 65535
  EXPECT_LT(wheel.count & 0xFFFF, 65500u);
  EXPECT_NEAR(wheel.odometry.distance_m(), 4.0, 1e-9);
  EXPECT_NEAR(wheel.odometry.speed_m_per_s(), 2.0, 1e-9);
}

TEST(Odometry, ThirtyTwoBitWrapFromA64BitReading) {
  Odometry odometry(config_100ppm());
  const std::uint64_t near_wrap = 0xFFFFFFF0ull;
  odometry.update(near_wrap, 0ns, 0ns);
  odometry.update(near_wrap + 0x20, 100ms, 100ms);  // the reader passes 0x1_0000_0010
  EXPECT_NEAR(odometry.distance_m(), 0.32, 1e-12);
}

TEST(Odometry, StandingStillDecaysToZero) {
  Wheel wheel{Odometry(config_100ppm()), 0, 0ns};
  wheel.run(0ns, 1s, 10ms, 1ms);
  const nanoseconds stop = wheel.last_edge;
  // 200 ms without a pulse: at most one pulse (1 cm) in 200 ms -> <= 0.05 m/s.
  wheel.odometry.update(wheel.count, wheel.last_edge, stop + 200ms);
  EXPECT_LE(wheel.odometry.speed_m_per_s(), 0.05 + 1e-12);
  EXPECT_GT(wheel.odometry.speed_m_per_s(), 0.0);
  wheel.odometry.update(wheel.count, wheel.last_edge, stop + 1s);
  EXPECT_DOUBLE_EQ(wheel.odometry.speed_m_per_s(), 0.0);
  EXPECT_NEAR(wheel.odometry.distance_m(), 1.0, 1e-9);  // distance is kept
}

TEST(Odometry, RestartAfterStandstillMeasuresFreshSpeed) {
  Wheel wheel{Odometry(config_100ppm()), 0, 0ns};
  wheel.run(0ns, 1s, 10ms, 1ms);
  wheel.odometry.update(wheel.count, wheel.last_edge, 5s);  // stood 4 s
  EXPECT_DOUBLE_EQ(wheel.odometry.speed_m_per_s(), 0.0);
  wheel.last_edge = 5s;
  wheel.run(5s, 5s + 500ms, 20ms, 1ms);  // 0.5 m/s
  EXPECT_NEAR(wheel.odometry.speed_m_per_s(), 0.5, 1e-9);
}

TEST(Odometry, DistanceAtInterpolatesAndExtrapolates) {
  Wheel wheel{Odometry(config_100ppm()), 0, 0ns};
  wheel.run(0ns, 1s, 10ms, 1ms);
  // Between two recorded edges (polling every 1 ms records each pulse): linear.
  EXPECT_NEAR(wheel.odometry.distance_at(503ms), 0.503, 1e-9);
  EXPECT_NEAR(wheel.odometry.distance_at(900ms), 0.90, 1e-9);
  // Ahead of the last edge: speed times the elapsed time, at most one pulse.
  EXPECT_NEAR(wheel.odometry.distance_at(1s + 4ms), 1.004, 1e-9);
  EXPECT_NEAR(wheel.odometry.distance_at(1s + 500ms), 1.01, 1e-9);
  // Older than the history: the oldest sample.
  EXPECT_GE(wheel.odometry.distance_at(-1s), 0.0);
}

TEST(Odometry, RejectsBadConfig) {
  OdometryConfig config = config_100ppm();
  config.pulses_per_metre = 0.0;
  EXPECT_THROW(Odometry{config}, std::invalid_argument);
  config = config_100ppm();
  config.counter_bits = 65;
  EXPECT_THROW(Odometry{config}, std::invalid_argument);
  config = config_100ppm();
  config.standstill_timeout = 0ns;
  EXPECT_THROW(Odometry{config}, std::invalid_argument);
}

}  // namespace
}  // namespace weedspray::control
