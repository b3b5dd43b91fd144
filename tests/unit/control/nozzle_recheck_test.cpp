// SPDX-License-Identifier: Apache-2.0
// NozzleRecheck against a scripted boom: each nozzle's true flow is its calibrated held-open
// flow times a true ratio, the meter counts the open nozzles' litres; the re-check holds one
// nozzle open at a time in the windows it is given and names the one off its calibration.
#include "control/nozzle_recheck.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace weedspray::control {
namespace {

constexpr double kTick = 0.002;  // a 500 Hz control loop
constexpr double kPulsesPerLitre = 8500.0;
constexpr double kPressure = 0.2;

struct ScriptedBoom {
  std::vector<NozzleLine> lines;
  std::array<double, 4> truth{1.0, 1.0, 1.0, 1.0};  // each nozzle's flow / its calibration
  double now_s = 0.0;
  double pulses = 0.0;  // fractional count; the meter reports its floor
  NozzleRecheck recheck{NozzleRecheckConfig{}};

  ScriptedBoom() {
    for (int i = 0; i < 4; ++i) {
      NozzleLine line;
      line.full_open_flow_l_per_min = 0.8 + 0.02 * i;
      lines.push_back(line);
    }
  }

  // One control tick: the re-check's duties (when it overrides) open the valves for this tick.
  void tick(bool window, bool pressure_ok = true) {
    RecheckInput in;
    in.now_s = now_s;
    in.window = window;
    in.pressure_ok = pressure_ok;
    in.meter_pulses = static_cast<std::uint64_t>(pulses);
    in.pulses_per_litre = kPulsesPerLitre;
    in.pressure_mpa = kPressure;
    recheck.step(in, lines);
    if (recheck.overriding()) {
      for (std::size_t i = 0; i < 4; ++i) {
        if (recheck.duties()[i] < 100.0) continue;
        const double flow = held_open_flow_l_per_min(lines[i], kPressure) * truth[i];
        pulses += flow / 60.0 * kTick * kPulsesPerLitre;
      }
    }
    now_s += kTick;
  }
  void run(double seconds, bool window, bool pressure_ok = true) {
    const int ticks = static_cast<int>(std::lround(seconds / kTick));
    for (int k = 0; k < ticks; ++k) tick(window, pressure_ok);
  }
};

TEST(NozzleRecheck, ANozzleReadingNinetyPercentIsAlarmedByName) {
  ScriptedBoom boom;
  boom.truth[2] = 0.9;
  boom.run(20.0, true);
  EXPECT_EQ(boom.recheck.completed(), 1U);
  EXPECT_NEAR(boom.recheck.ratio(2), 0.9, 0.005);
  EXPECT_EQ(boom.recheck.alarmed_nozzle(), 2);
  EXPECT_EQ(boom.recheck.warned_nozzle(), 2);
  EXPECT_NEAR(boom.recheck.scale(2), 0.9, 0.005);
  for (std::size_t i : {0U, 1U, 3U}) EXPECT_NEAR(boom.recheck.ratio(i), 1.0, 0.005);
  // The scaled line promises what the nozzle now gives.
  const NozzleLine scaled = scaled_line(boom.lines[2], boom.recheck.scale(2));
  EXPECT_NEAR(held_open_flow_l_per_min(scaled, kPressure),
              0.9 * held_open_flow_l_per_min(boom.lines[2], kPressure), 0.005);
  EXPECT_NEAR(scaled.slope_l_per_min_per_pct,
              boom.recheck.scale(2) * boom.lines[2].slope_l_per_min_per_pct, 1e-12);
}

TEST(NozzleRecheck, ANozzleReadingNinetySevenPercentIsNeitherWarnedNorAlarmed) {
  ScriptedBoom boom;
  boom.truth[1] = 0.97;
  boom.run(20.0, true);
  EXPECT_NEAR(boom.recheck.ratio(1), 0.97, 0.005);
  EXPECT_EQ(boom.recheck.warned_nozzle(), -1);
  EXPECT_EQ(boom.recheck.alarmed_nozzle(), -1);
}

TEST(NozzleRecheck, ANozzleReadingNinetyThreePercentIsWarnedNotAlarmed) {
  ScriptedBoom boom;
  boom.truth[3] = 0.93;
  boom.run(20.0, true);
  EXPECT_EQ(boom.recheck.warned_nozzle(), 3);
  EXPECT_EQ(boom.recheck.alarmed_nozzle(), -1);
}

TEST(NozzleRecheck, HoldsOneNozzleOpenAtATimeAndReleasesTheBoomWhenDone) {
  ScriptedBoom boom;
  const NozzleRecheckConfig& c = boom.recheck.config();
  const double per_nozzle = c.settle_s + c.measure_s;
  for (int i = 0; i < 4; ++i) {
    boom.run(per_nozzle * 0.5, true);
    ASSERT_TRUE(boom.recheck.overriding());
    EXPECT_EQ(boom.recheck.current_nozzle(), i);
    for (int j = 0; j < 4; ++j)
      EXPECT_EQ(boom.recheck.duties()[static_cast<std::size_t>(j)], i == j ? 100.0 : 0.0);
    boom.run(per_nozzle * 0.5, true);
  }
  boom.run(0.1, true);
  EXPECT_FALSE(boom.recheck.overriding());
  EXPECT_FALSE(boom.recheck.in_progress());
  for (std::size_t i = 0; i < 4; ++i) EXPECT_GT(boom.recheck.measured_at_s(i), 0.0);
}

// Crop again while a nozzle is held open: the override ends on that very call, and the next
// window reads that nozzle again from its settle (the abandoned reading is not used).
TEST(NozzleRecheck, AWindowClosingMidNozzleEndsTheOverrideOnThatCall) {
  ScriptedBoom boom;
  boom.truth[1] = 0.9;
  const NozzleRecheckConfig& c = boom.recheck.config();
  boom.run(c.settle_s + c.measure_s + c.settle_s + 0.5 * c.measure_s, true);  // into nozzle 1
  ASSERT_TRUE(boom.recheck.overriding());
  ASSERT_EQ(boom.recheck.current_nozzle(), 1);
  boom.tick(false);
  EXPECT_FALSE(boom.recheck.overriding());
  for (double duty : boom.recheck.duties()) EXPECT_EQ(duty, 0.0);
  EXPECT_LT(boom.recheck.measured_at_s(1), 0.0);
  boom.run(30.0, false);  // spraying crop: nothing held open
  EXPECT_FALSE(boom.recheck.overriding());
  EXPECT_TRUE(boom.recheck.in_progress());
  boom.tick(true);  // the next window resumes at nozzle 1, whatever the interval
  EXPECT_TRUE(boom.recheck.overriding());
  EXPECT_EQ(boom.recheck.current_nozzle(), 1);
  boom.run(3.0 * (c.settle_s + c.measure_s) + 0.1, true);
  EXPECT_EQ(boom.recheck.completed(), 1U);
  EXPECT_EQ(boom.recheck.alarmed_nozzle(), 1);
  EXPECT_NEAR(boom.recheck.ratio(1), 0.9, 0.005);
}

// A whole-boom re-check at most every interval_s: a window before it is due is left alone.
TEST(NozzleRecheck, ReChecksAtMostEveryInterval) {
  ScriptedBoom boom;
  const double interval = boom.recheck.config().interval_s;
  boom.run(15.0, true);  // the first window: the job's start
  EXPECT_EQ(boom.recheck.completed(), 1U);
  boom.run(10.0, false);
  boom.run(15.0, true);  // 25 s after the first start: not due
  EXPECT_EQ(boom.recheck.completed(), 1U);
  EXPECT_FALSE(boom.recheck.overriding());
  boom.run(interval - 40.0 + 1.0, false);
  boom.tick(true);  // due again
  EXPECT_TRUE(boom.recheck.overriding());
  boom.run(15.0, true);
  EXPECT_EQ(boom.recheck.completed(), 2U);
  // reset(): a new job re-checks at its first window.
  boom.recheck.reset();
  boom.tick(true);
  EXPECT_TRUE(boom.recheck.overriding());
}

// A nozzle already blocked when the job starts is named at the first window: the reading is
// against its calibration, not against anything learned in the job.
TEST(NozzleRecheck, ANozzleBlockedBeforeTheJobIsNamedAtTheFirstWindow) {
  ScriptedBoom boom;
  boom.truth[0] = 0.88;
  const NozzleRecheckConfig& c = boom.recheck.config();
  boom.run(static_cast<double>(c.nozzles) * (c.settle_s + c.measure_s) + 0.1, true);
  EXPECT_EQ(boom.recheck.completed(), 1U);
  EXPECT_EQ(boom.recheck.alarmed_nozzle(), 0);
}

// The settle counts only while the pressure is fine; a dip while reading restarts the nozzle.
TEST(NozzleRecheck, ReadsOnlyAtAGoodPressure) {
  ScriptedBoom boom;
  const NozzleRecheckConfig& c = boom.recheck.config();
  boom.run(5.0, true, false);
  EXPECT_TRUE(boom.recheck.overriding());  // held open, off crop, while the pressure comes up
  EXPECT_EQ(boom.recheck.current_nozzle(), 0);
  boom.run(c.settle_s + 0.5 * c.measure_s, true);
  boom.run(0.1, true, false);
  boom.run(0.5 * c.measure_s + 0.1, true);
  EXPECT_LT(boom.recheck.measured_at_s(0), 0.0);  // restarted: not read yet
  boom.run(c.settle_s + c.measure_s, true);
  EXPECT_GT(boom.recheck.measured_at_s(0), 0.0);
}

TEST(NozzleRecheck, ValidatesItsConfig) {
  NozzleRecheckConfig c;
  c.nozzles = 0;
  EXPECT_THROW(NozzleRecheck{c}, std::invalid_argument);
  c = {};
  c.nozzles = kMaxRecheckNozzles + 1;
  EXPECT_THROW(NozzleRecheck{c}, std::invalid_argument);
  c = {};
  c.measure_s = 0.0;
  EXPECT_THROW(NozzleRecheck{c}, std::invalid_argument);
  c = {};
  c.alarm_fraction = 0.04;
  EXPECT_THROW(NozzleRecheck{c}, std::invalid_argument);
  c = {};
  c.tolerance = 0.05;
  EXPECT_THROW(NozzleRecheck{c}, std::invalid_argument);
}

}  // namespace
}  // namespace weedspray::control
