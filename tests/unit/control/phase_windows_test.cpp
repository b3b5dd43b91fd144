// SPDX-License-Identifier: Apache-2.0
// Phase windows for nozzle health (control/phase_windows.hpp): a staggered boom whose
// valve writes and meter are known exactly, sampled like the control loop (every 2 ms, some
// cycles missed): each window's open times are the true ones, its volume the true volume a meter
// lag later, and the detector fed them learns each nozzle's own flow.
#include "control/phase_windows.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "control/nozzle_health.hpp"

namespace weedspray::control {
namespace {

using namespace std::chrono_literals;
using Nanos = std::chrono::nanoseconds;

// 4 valves at 5 Hz, valve k's period starting k x 50 ms after the schedule's start, open for
// on[k] of it; each open valve passes flow_l_per_s[k]; the meter sees the flow 30 ms late.
struct StaggeredBoom {
  Nanos start = 1000ms;
  Nanos period = 200ms;
  std::array<Nanos, 4> on{30ms, 60ms, 90ms, 120ms};
  std::array<double, 4> flow_l_per_s{0.010, 0.012, 0.009, 0.011};
  double pulses_per_litre = 8500.0;

  bool open(std::size_t k, Nanos t) const {
    if (t < start) return false;
    const Nanos phase = (t - start - static_cast<std::int64_t>(k) * 50ms + 10 * period) % period;
    return phase < on[k];
  }
  std::uint32_t mask(Nanos t) const {
    std::uint32_t m = 0;
    for (std::size_t k = 0; k < 4; ++k)
      if (open(k, t)) m |= 1U << k;
    return m;
  }
  // The latest valve write at or before t (edges on whole milliseconds here).
  Nanos last_write(Nanos t) const {
    Nanos w = std::chrono::floor<std::chrono::milliseconds>(t);
    while (w > start && mask(w) == mask(w - 1ms)) w -= 1ms;
    return w;
  }
  // The meter's whole pulses at `now`: the flow through the open valves 30 ms before, added up
  // in 100 us steps from `until` (the caller's running total and time).
  std::uint64_t meter_pulses(double& litres, Nanos& until, Nanos now) const {
    for (; until + 30ms < now; until += 100us) {
      for (std::size_t k = 0; k < 4; ++k)
        if (open(k, until)) litres += flow_l_per_s[k] * 100e-6;
    }
    return static_cast<std::uint64_t>(litres * pulses_per_litre);
  }
  // Exact open time of valve k in [a, b) (1 us steps) and litres through all of them.
  double open_s(std::size_t k, Nanos a, Nanos b) const {
    std::int64_t us = 0;
    for (Nanos t = a; t < b; t += 1us) us += open(k, t) ? 1 : 0;
    return static_cast<double>(us) * 1e-6;
  }
};

TEST(PhaseWindows, EachWindowHoldsTheTrueOpenTimesAndTheVolumeAMeterLagLater) {
  const StaggeredBoom boom;
  PhaseWindows windows(50ms, 30ms);
  double metered_l = 0.0;  // the meter's true volume so far (30 ms behind the valves)
  Nanos metered_until = boom.start;
  int windows_seen = 0;
  for (Nanos now = boom.start + 7ms; now < boom.start + 2s; now += 2ms) {
    if ((now / 2ms) % 17 == 0) continue;  // the stats slot was busy this cycle
    const std::uint64_t pulses = boom.meter_pulses(metered_l, metered_until, now);
    if (!windows.update(boom.start, boom.mask(now), boom.last_write(now), now, pulses,
                        boom.pulses_per_litre)) {
      continue;
    }
    // The window that closed a lag ago: [start + j x 50 ms, + 50 ms).
    const std::int64_t j = (now - 30ms - boom.start) / 50ms - 1;
    const Nanos a = boom.start + j * 50ms;
    double expected_l = 0.0;
    for (std::size_t k = 0; k < 4; ++k) {
      const double open = boom.open_s(k, a, a + 50ms);
      EXPECT_NEAR(windows.open_s()[k], open, 1e-9) << "valve " << k << " window " << j;
      expected_l += open * boom.flow_l_per_s[k];
    }
    // Whole pulses, read up to one cycle late: within 2 pulses and 2 ms of flow.
    EXPECT_NEAR(windows.metered_l(), expected_l, 2.0 / boom.pulses_per_litre + 0.042 * 0.002)
        << "window " << j;
    EXPECT_DOUBLE_EQ(windows.window_s(), 0.05);
    ++windows_seen;
  }
  EXPECT_GE(windows_seen, 35);  // 40 windows in 2 s, the first (partial) only marks the meter
}

TEST(PhaseWindows, TheDetectorFedThemLearnsEachNozzlesFlow) {
  StaggeredBoom boom;
  control::NozzleHealthConfig config;
  config.baseline_s = 5.0;
  // Valve 0's pulses are 30 ms, which the CUSUM leaves out on a real boom (mostly the valves'
  // delays); this scripted boom's flow follows its open times exactly.
  config.min_pulse_s = 0.0;
  control::NozzleHealth health(config);
  PhaseWindows windows(50ms, 30ms);
  double metered_l = 0.0;
  Nanos metered_until = boom.start;
  for (Nanos now = boom.start + 1ms; now < boom.start + 12s; now += 2ms) {
    if (now == boom.start + 8001ms) boom.flow_l_per_s[2] *= 0.7;  // nozzle 2 30 % blocked
    const std::uint64_t pulses = boom.meter_pulses(metered_l, metered_until, now);
    if (windows.update(boom.start, boom.mask(now), boom.last_write(now), now, pulses,
                       boom.pulses_per_litre)) {
      health.add_window(windows.open_s(), windows.metered_l(), windows.window_s());
    }
    if (now == boom.start + 7001ms) {
      ASSERT_TRUE(health.baseline_ready());
      // ~12 whole pulses a window: a few % of scatter, well inside the 12 % alarm band.
      for (std::size_t k = 0; k < 4; ++k) EXPECT_NEAR(health.ratio(k), 1.0, 0.05) << k;
      EXPECT_EQ(health.alarmed_nozzle(), -1);
    }
  }
  EXPECT_EQ(health.alarmed_nozzle(), 2);
  EXPECT_LT(health.ratio(2), 0.88);
}

}  // namespace
}  // namespace weedspray::control
