// NozzleHealth on synthetic windows: staggered phases make the nozzles separable, a blocked
// one is named, healthy ones are not, synchronous phases cannot tell nozzles apart.
#include "control/nozzle_health.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <random>
#include <stdexcept>

namespace weedspray::control {
namespace {

constexpr double kPeriod = 1.0 / 3.0;  // 3 Hz PWM
constexpr double kWindow = kPeriod / 4.0;

// Open time of a nozzle with phase offset `phase` [periods] and duty d in window w of a period.
double open_in_window(double phase, double duty, int w) {
  double open = 0.0;
  const double a = w * 0.25, b = a + 0.25;
  for (double start : {phase - 1.0, phase}) {  // the pulse and its wrap from the last period
    const double lo = std::max(a, start), hi = std::min(b, start + duty);
    open += std::max(0.0, hi - lo);
  }
  return open * kPeriod;
}

struct Feed {
  std::array<double, 4> flow_l_per_s{0.011, 0.0105, 0.0112, 0.0108};
  bool staggered = true;
  std::mt19937_64 rng{3};
  double metered_l = 0.0;    // true volume through the meter
  std::uint64_t pulses = 0;  // what the meter counted (8500 pulses/L)
  // One second of windows with duties redrawn in [0.3, 0.9].
  void second(NozzleHealth& h) {
    std::uniform_real_distribution<double> duty(0.3, 0.9);
    std::array<double, 4> d{};
    for (auto& x : d) x = duty(rng);
    for (int p = 0; p < 3; ++p)
      for (int w = 0; w < 4; ++w) {
        std::array<double, 4> open{};
        double v = 0.0;
        for (int i = 0; i < 4; ++i) {
          open[static_cast<std::size_t>(i)] =
              open_in_window(staggered ? i * 0.25 : 0.0, d[static_cast<std::size_t>(i)], w);
          v += open[static_cast<std::size_t>(i)] * flow_l_per_s[static_cast<std::size_t>(i)];
        }
        // The meter's pulse count quantises the volume (a pulse is 0.12 mL).
        metered_l += v;
        const auto now = static_cast<std::uint64_t>(metered_l * 8500.0);
        h.add_window(open, static_cast<double>(now - pulses) / 8500.0, kWindow);
        pulses = now;
      }
  }
};

TEST(NozzleHealth, LearnsTheBaselineThenNamesTheBlockedNozzle) {
  NozzleHealth h(NozzleHealthConfig{});
  Feed feed;
  for (int s = 0; s < 120; ++s) feed.second(h);
  ASSERT_TRUE(h.baseline_ready());
  for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(h.ratio(i), 1.0, 0.05);
  EXPECT_EQ(h.alarmed_nozzle(), -1);
  feed.flow_l_per_s[2] *= 0.8;  // 20 % blocked
  int seconds = 0;
  while (h.alarmed_nozzle() < 0 && seconds < 30) {
    feed.second(h);
    ++seconds;
  }
  EXPECT_EQ(h.alarmed_nozzle(), 2);
  EXPECT_LE(seconds, 10);
  EXPECT_NEAR(h.ratio(2), 0.8, 0.08);
}

// Equal duties (a uniform field): staggered phases rotate the window mixes and the nozzles
// separate; synchronous phases give every nozzle the same open time in every window, and no
// nozzle can be told from another.
bool separable(bool staggered, double duty) {
  NozzleHealth h(NozzleHealthConfig{});
  for (int k = 0; k < 1200; ++k) {  // 100 s: past the 60 s baseline
    std::array<double, 4> open{};
    const int w = k % 4;
    for (int i = 0; i < 4; ++i)
      open[static_cast<std::size_t>(i)] = open_in_window(staggered ? i * 0.25 : 0.0, duty, w);
    h.add_window(open, 0.001, kWindow);
  }
  return h.baseline_ready();
}

TEST(NozzleHealth, StaggeredPhasesSeparateTheNozzlesAndSynchronousDoNot) {
  EXPECT_TRUE(separable(true, 0.6));
  EXPECT_TRUE(separable(true, 0.3));
  EXPECT_FALSE(separable(false, 0.6));
  // Four nozzles at exactly 50 % staggered by T/4: the alternating pattern is invisible (the
  // window mixes form a singular circulant); real variable-rate duties are rarely all 50 %.
  EXPECT_FALSE(separable(true, 0.5));
}

TEST(NozzleHealth, RejectsBadConfig) {
  NozzleHealthConfig c;
  c.nozzles = 0;
  EXPECT_THROW(NozzleHealth{c}, std::invalid_argument);
  c = {};
  c.alarm_fraction = 1.5;
  EXPECT_THROW(NozzleHealth{c}, std::invalid_argument);
}

}  // namespace
}  // namespace weedspray::control
