// SPDX-License-Identifier: Apache-2.0
// Lateness figures of the real-time loops: the histogram, PeriodicLoop's misses and the valve
// driver's missed edges (what the daemon's control_overruns alarm counts).
#include <gtest/gtest.h>

#include <stop_token>

#include "control/pwm_schedule.hpp"
#include "io/lateness_histogram.hpp"
#include "io/loop_watch.hpp"
#include "io/realtime.hpp"
#include "io/sim/manual_clock.hpp"
#include "io/sim/memory_output_bank.hpp"
#include "io/valve_pwm_driver.hpp"

namespace weedspray::io {
namespace {

using namespace std::chrono_literals;
using std::chrono::nanoseconds;

TEST(LatenessHistogram, BucketEdgesAreTheR10SeriesFrom1usTo1s) {
  EXPECT_EQ(LatenessHistogram::upper_edge_ns(0), 1'000);
  EXPECT_EQ(LatenessHistogram::upper_edge_ns(1), 1'250);
  EXPECT_EQ(LatenessHistogram::upper_edge_ns(9), 8'000);
  EXPECT_EQ(LatenessHistogram::upper_edge_ns(10), 10'000);
  EXPECT_EQ(LatenessHistogram::upper_edge_ns(37), 5'000'000);  // the default tolerance
  EXPECT_EQ(LatenessHistogram::upper_edge_ns(60), 1'000'000'000);
  for (std::size_t i = 1; i + 1 < LatenessHistogram::kBuckets; ++i) {
    EXPECT_GT(LatenessHistogram::upper_edge_ns(i), LatenessHistogram::upper_edge_ns(i - 1)) << i;
  }
}

TEST(LatenessHistogram, QuantilesAreTheBucketEdgeAtOrAboveTheTrueValue) {
  LatenessHistogram h;
  EXPECT_EQ(h.quantile(0.99), 0ns) << "empty";
  for (int i = 0; i < 990; ++i) h.record(30us);  // 30 us lies in (25, 31.5] us
  for (int i = 0; i < 9; ++i) h.record(700us);   // (630, 800] us
  h.record(7ms);                                 // (6.3, 8] ms
  EXPECT_EQ(h.count(), 1000U);
  EXPECT_EQ(h.quantile(0.5), 31'500ns);
  EXPECT_EQ(h.quantile(0.99), 31'500ns) << "the 990th sample is still 30 us";
  EXPECT_EQ(h.quantile(0.995), 800us);
  EXPECT_EQ(h.quantile(1.0), 7ms) << "never above the largest sample";
  EXPECT_EQ(h.max(), 7ms);
  EXPECT_EQ(h.count_above(5ms), 1U);
  EXPECT_EQ(h.count_above(500us), 10U);
  h.record(-3us);  // woke early (a clock step): the lowest bucket, not a crash
  EXPECT_EQ(h.count(), 1001U);
}

// A clock whose every sleep overshoots by `late`: a machine that wakes its threads late.
class LateClock final : public Clock {
 public:
  explicit LateClock(nanoseconds late) : late_(late) {}
  nanoseconds now() const noexcept override { return inner.now(); }
  void sleep_until(nanoseconds t) noexcept override {
    inner.sleep_until(t + late_);
    if (inner.now() >= stop_at) stop.request_stop();
  }
  sim::ManualClock inner;
  nanoseconds stop_at{2s};
  std::stop_source stop;

 private:
  nanoseconds late_;
};

TEST(PeriodicLoop, RecordsEveryWakeAndCountsMissesBeyondTheTolerance) {
  LateClock clock(3ms);
  LatenessHistogram h;
  PeriodicLoop strict(clock, 10ms, 0ns, &h, 2ms);
  for (int k = 0; k < 50; ++k) strict.wait_next();
  EXPECT_EQ(h.count(), 50U);
  EXPECT_EQ(h.max(), 3ms);
  EXPECT_EQ(strict.misses(), 50U) << "3 ms late > 2 ms tolerance";
  EXPECT_EQ(strict.overruns(), 0U) << "but no period is lost";

  LateClock clock2(3ms);
  PeriodicLoop lenient(clock2, 10ms, 0ns, nullptr, 5ms);
  for (int k = 0; k < 50; ++k) lenient.wait_next();
  EXPECT_EQ(lenient.misses(), 0U);
}

struct LateValveRig {
  explicit LateValveRig(nanoseconds late, nanoseconds tolerance) : clock(late) {
    ValvePwmDriverConfig config;
    config.command_expiry = 10s;
    config.miss_tolerance = tolerance;
    config.lateness = &lateness;
    driver.emplace(clock, bank, schedule, config);
    ValveCommand c;
    c.valve_count = 4;
    for (int v = 0; v < 4; ++v) c.duty_pct[v] = 20.0 + 15.0 * v;
    driver->command(c);
    driver->run(clock.stop.get_token());
  }
  LateClock clock;
  sim::MemoryOutputBank bank{4, 0, clock, 1000};
  control::PwmConfig pwm_config{};
  control::PwmSchedule schedule{pwm_config};
  LatenessHistogram lateness;
  std::optional<ValvePwmDriver<control::PwmSchedule>> driver;
};

TEST(ValvePwmDriver, CountsEdgesLaterThanTheToleranceAsMissed) {
  LateValveRig late(7ms, 5ms);
  const ValvePwmStats stats = late.driver->stats();
  ASSERT_GT(stats.edges_written, 20U);
  // Every edge after the first (written at the schedule's start, i.e. at once) is 7 ms late.
  EXPECT_EQ(stats.missed_edges, stats.edges_written - 1);
  EXPECT_EQ(late.lateness.count(), stats.edges_written);
  EXPECT_EQ(late.lateness.max(), 7ms);

  LateValveRig on_time(1ms, 5ms);
  EXPECT_EQ(on_time.driver->stats().missed_edges, 0U);
  EXPECT_GT(on_time.driver->stats().late_edges, 0U) << "1 ms is late (> 0.5 ms), not a miss";
}

TEST(LoopWatch, StaleOnlyWhenTheCounterStaysStillLongerThanTheTimeout) {
  LoopWatch watch(50ms);
  EXPECT_FALSE(watch.stale(7, 0ms)) << "first sight";
  EXPECT_FALSE(watch.stale(7, 50ms)) << "still within the timeout";
  EXPECT_TRUE(watch.stale(7, 51ms));
  EXPECT_FALSE(watch.stale(8, 52ms)) << "moving again";
  EXPECT_FALSE(watch.stale(8, 100ms));
  EXPECT_TRUE(watch.stale(8, 103ms));
}

}  // namespace
}  // namespace weedspray::io
