// SPDX-License-Identifier: Apache-2.0
#include "io/realtime.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <set>

#include "io/sim/manual_clock.hpp"

namespace weedspray::io {
namespace {

using namespace std::chrono_literals;

TEST(Realtime, PriorityTableIsComplete) {
  std::set<ThreadRole> roles;
  for (const auto& p : kThreadPriorities) {
    roles.insert(p.role);
    EXPECT_LE(p.name.size(), 15U) << p.name;
    EXPECT_GE(p.fifo_priority, 0);
    EXPECT_LE(p.fifo_priority, 99);
  }
  EXPECT_EQ(roles.size(), kThreadPriorities.size());
  EXPECT_GT(thread_priority(ThreadRole::kValvePwm).fifo_priority,
            thread_priority(ThreadRole::kPressureLoop).fifo_priority);
  EXPECT_EQ(thread_priority(ThreadRole::kModbus).fifo_priority, 0);
  // The E-stop's reaction writes the valves and pump safe: nothing of the daemon delays it.
  for (const auto& p : kThreadPriorities) {
    if (p.role != ThreadRole::kEstop) {
      EXPECT_GT(thread_priority(ThreadRole::kEstop).fifo_priority, p.fifo_priority) << p.name;
    }
  }
}

TEST(Realtime, ThreadRunsWithAReportedStatus) {
  std::atomic<bool> ran{false};
  RealtimeThread t(ThreadRole::kValvePwm, [&](std::stop_token) { ran = true; });
  EXPECT_TRUE(t.status() == RtStatus::kRealtime || t.status() == RtStatus::kNoPermission)
      << to_string(t.status());
  t.stop_and_join();
  EXPECT_TRUE(ran);
  RealtimeThread normal(ThreadRole::kModbus, [](std::stop_token) {});
  EXPECT_EQ(normal.status(), RtStatus::kNormalPriority);
}

TEST(Realtime, ThreadStopsOnRequest) {
  std::atomic<int> loops{0};
  RealtimeThread t(ThreadRole::kCamera, [&](std::stop_token stop) {
    while (!stop.stop_requested()) ++loops;
  });
  t.stop_and_join();
  EXPECT_FALSE(t.joinable());
}

// A clock where "work" takes time: each now() after a wake adds the work duration.
class WorkingClock final : public Clock {
 public:
  std::chrono::nanoseconds now() const noexcept override { return inner.now(); }
  void sleep_until(std::chrono::nanoseconds t) noexcept override { inner.sleep_until(t); }
  sim::ManualClock inner;
};

TEST(PeriodicLoop, AbsoluteDeadlinesWithoutDrift) {
  sim::ManualClock clock;
  PeriodicLoop loop(clock, 10ms, 0ns);
  for (int k = 0; k < 100; ++k) {
    EXPECT_EQ(loop.wait_next(), k * 10ms);
    clock.advance(3ms);  // work inside the period: no effect on the next deadline
  }
  EXPECT_EQ(loop.overruns(), 0U);
  EXPECT_EQ(loop.cycles(), 100U);
}

TEST(PeriodicLoop, CountsOverrunsAndSkipsMissedDeadlines) {
  WorkingClock clock;
  PeriodicLoop loop(clock, 10ms, 0ns);
  EXPECT_EQ(loop.wait_next(), 0ms);
  clock.inner.advance(35ms);  // a cycle that took 3.5 periods
  EXPECT_EQ(loop.wait_next(), 10ms) << "the due deadline is served, late";
  EXPECT_EQ(loop.overruns(), 2U) << "deadlines 20 and 30 are skipped";
  EXPECT_EQ(loop.wait_next(), 40ms) << "no burst of catch-up cycles";
  EXPECT_EQ(loop.max_lateness(), 25ms);
}

}  // namespace
}  // namespace weedspray::io
