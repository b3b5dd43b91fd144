// SPDX-License-Identifier: Apache-2.0
#include "control/pwm_schedule.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace weedspray::control {
namespace {

using namespace std::chrono_literals;
using std::chrono::nanoseconds;

PwmConfig four_valves(PwmPhaseMode mode = PwmPhaseMode::kStaggered) {
  PwmConfig config;
  config.valve_count = 4;
  config.frequency_hz = 5.0;  // T = 200 ms
  config.phase_mode = mode;
  return config;
}

TEST(PwmSchedule, OuterFirstOrder) {
  EXPECT_EQ(outer_first_order(4), (std::vector<std::size_t>{0, 3, 1, 2}));
  EXPECT_EQ(outer_first_order(5), (std::vector<std::size_t>{0, 4, 1, 3, 2}));
  EXPECT_EQ(outer_first_order(1), (std::vector<std::size_t>{0}));
}

TEST(PwmSchedule, OffsetsFollowTheOrder) {
  const PwmSchedule pwm(four_valves());
  EXPECT_EQ(pwm.period(), 200ms);
  EXPECT_EQ(pwm.phase_offset(0), 0ms);    // A first
  EXPECT_EQ(pwm.phase_offset(3), 50ms);   // then D
  EXPECT_EQ(pwm.phase_offset(1), 100ms);  // B
  EXPECT_EQ(pwm.phase_offset(2), 150ms);  // C
  PwmConfig custom = four_valves();
  custom.order = {2, 1, 0, 3};
  const PwmSchedule other(custom);
  EXPECT_EQ(other.phase_offset(2), 0ms);
  EXPECT_EQ(other.phase_offset(3), 150ms);
}

TEST(PwmSchedule, StaggeredEdgesAtHalfDuty) {
  PwmSchedule pwm(four_valves());
  const std::vector<double> duties{50, 50, 50, 50};
  pwm.set_duties(duties);
  const nanoseconds t0 = 1s;
  pwm.start(t0);
  const std::vector<PwmEdge> expected{
      {t0, 0b0001},          // A opens
      {t0 + 50ms, 0b1001},   // D opens
      {t0 + 100ms, 0b1010},  // A closes, B opens (merged)
      {t0 + 150ms, 0b0110},  // D closes, C opens
      {t0 + 200ms, 0b0101},  // A opens, B closes
      {t0 + 250ms, 0b1001},  // D opens, C closes
  };
  for (const PwmEdge& e : expected) {
    const PwmEdge got = pwm.next_edge();
    EXPECT_EQ(got.time, e.time);
    EXPECT_EQ(got.valve_mask, e.valve_mask) << "at " << (e.time - t0).count() / 1000000 << " ms";
  }
}

TEST(PwmSchedule, SynchronousModeSwitchesTogether) {
  PwmSchedule pwm(four_valves(PwmPhaseMode::kSynchronous));
  pwm.set_duties(std::vector<double>{25, 50, 75, 100});
  pwm.start(0ns);
  EXPECT_EQ(pwm.next_edge().valve_mask, 0b1111u);
  PwmEdge e = pwm.next_edge();
  EXPECT_EQ(e.time, 50ms);
  EXPECT_EQ(e.valve_mask, 0b1110u);
  e = pwm.next_edge();
  EXPECT_EQ(e.time, 100ms);
  EXPECT_EQ(e.valve_mask, 0b1100u);
  e = pwm.next_edge();
  EXPECT_EQ(e.time, 150ms);
  EXPECT_EQ(e.valve_mask, 0b1000u);
  e = pwm.next_edge();
  EXPECT_EQ(e.time, 200ms);
  EXPECT_EQ(e.valve_mask, 0b1111u);
}

TEST(PwmSchedule, DutyIsLatchedAtThePeriodStart) {
  PwmConfig config = four_valves();
  config.valve_count = 1;
  PwmSchedule pwm(config);
  pwm.set_duty(0, 50);
  pwm.start(0ns);
  EXPECT_EQ(pwm.next_edge().valve_mask, 1u);  // t = 0, open for 100 ms
  pwm.set_duty(0, 10);                        // mid-period: must not shorten this pulse
  EXPECT_DOUBLE_EQ(pwm.valve_state(0).latched_duty_pct, 50.0);
  PwmEdge e = pwm.next_edge();
  EXPECT_EQ(e.time, 100ms);
  EXPECT_EQ(e.valve_mask, 0u);
  e = pwm.next_edge();
  EXPECT_EQ(e.time, 200ms);
  EXPECT_EQ(e.valve_mask, 1u);
  EXPECT_DOUBLE_EQ(pwm.valve_state(0).latched_duty_pct, 10.0);
  EXPECT_EQ(pwm.valve_state(0).on_time, 20ms);
  EXPECT_EQ(pwm.next_edge().time, 220ms);
}

TEST(PwmSchedule, MinimumOnAndOffTimesRoundToTheNearer) {
  PwmConfig config = four_valves();
  config.min_on_time = 20ms;
  config.min_off_time = 20ms;
  const PwmSchedule pwm(config);
  EXPECT_EQ(pwm.on_time_for(4.0), 0ms);     // 8 ms < 10 ms: closed
  EXPECT_EQ(pwm.on_time_for(5.0), 20ms);    // 10 ms: half-way rounds up to the minimum
  EXPECT_EQ(pwm.on_time_for(7.5), 20ms);    // 15 ms -> 20 ms
  EXPECT_EQ(pwm.on_time_for(10.0), 20ms);   // exactly the minimum
  EXPECT_EQ(pwm.on_time_for(96.0), 200ms);  // off 8 ms: open all period
  EXPECT_EQ(pwm.on_time_for(95.0), 180ms);  // off 10 ms -> 20 ms
  EXPECT_EQ(pwm.on_time_for(50.0), 100ms);
  EXPECT_DOUBLE_EQ(pwm.effective_duty_pct(7.5), 10.0);
}

TEST(PwmSchedule, OpenTimeOverManyPeriodsMatchesLatchedDuties) {
  PwmConfig config = four_valves();
  config.valve_count = 7;
  config.frequency_hz = 3.0;  // T = 333333333 ns: the offsets do not divide evenly
  config.min_on_time = 15ms;
  config.min_off_time = 10ms;
  PwmSchedule pwm(config);
  const nanoseconds period = pwm.period();
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> duty(0.0, 100.0);
  const nanoseconds t0 = 5s;
  pwm.start(t0);
  constexpr int kPeriods = 150;
  // Per valve: the on-time latched at each of its first kPeriods period starts.
  std::vector<nanoseconds> expected(7, 0ns);
  std::vector<int> periods_seen(7, 0);
  std::vector<PwmEdge> edges;
  nanoseconds last = t0 - 1ns;
  while (last < t0 + (kPeriods + 1) * period) {
    if (rng() % 3 == 0) pwm.set_duty(rng() % 7, duty(rng));
    const PwmEdge e = pwm.next_edge();
    ASSERT_GT(e.time, last);
    ASSERT_LE(e.time - last, period / 7 + 1ns);  // staggered: a period start every T/N
    last = e.time;
    edges.push_back(e);
    for (std::size_t v = 0; v < 7; ++v) {
      const PwmValveState s = pwm.valve_state(v);
      if (s.period_start == e.time && periods_seen[v] < kPeriods) {
        ++periods_seen[v];
        expected[v] += s.on_time;
        EXPECT_EQ(s.on_time, pwm.on_time_for(s.latched_duty_pct));
        EXPECT_EQ(s.open, s.on_time > 0ns);
      }
    }
  }
  for (std::size_t v = 0; v < 7; ++v) {
    // Integrate the valve's bit of the edge masks over its first kPeriods periods.
    const nanoseconds from = t0 + pwm.phase_offset(v);
    const nanoseconds to = from + kPeriods * period;
    nanoseconds open = 0ns;
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
      if (!(edges[i].valve_mask >> v & 1u)) continue;
      const nanoseconds a = std::max(edges[i].time, from);
      const nanoseconds b = std::min(edges[i + 1].time, to);
      if (b > a) open += b - a;
    }
    EXPECT_EQ(periods_seen[v], kPeriods);
    EXPECT_EQ(open, expected[v]) << "valve " << v;
  }
}

TEST(PwmSchedule, MaskAtPredictsTheEdgesWhileDutiesHold) {
  PwmConfig config = four_valves();
  config.min_on_time = 12ms;
  PwmSchedule pwm(config);
  pwm.set_duties(std::vector<double>{35, 0, 100, 72.5});
  pwm.start(2s);
  pwm.next_edge();
  pwm.next_edge();
  pwm.set_duty(1, 5);  // requested, latched later: 10 ms -> rounds to 12 ms
  // Predict from here, then walk the real edges and compare every 1 ms.
  std::vector<std::uint32_t> predicted;
  const nanoseconds from = pwm.last_edge_time();
  for (int i = 0; i < 1000; ++i) predicted.push_back(pwm.mask_at(from + i * 1ms));
  std::uint32_t mask = pwm.current_mask();
  PwmEdge next = pwm.next_edge();
  for (int i = 0; i < 1000; ++i) {
    const nanoseconds t = from + i * 1ms;
    while (next.time <= t) {
      mask = next.valve_mask;
      next = pwm.next_edge();
    }
    ASSERT_EQ(predicted[i], mask) << "at +" << i << " ms";
  }
  EXPECT_EQ(pwm.valve_state_at(1, from + 900ms).on_time, 12ms);
}

TEST(PwmSchedule, ClosedValvesStillGiveEdgesAtPeriodStarts) {
  PwmSchedule pwm(four_valves());
  pwm.start(0ns);
  for (int i = 0; i < 8; ++i) {
    const PwmEdge e = pwm.next_edge();
    EXPECT_EQ(e.time, i * 50ms);
    EXPECT_EQ(e.valve_mask, 0u);
  }
}

TEST(PwmSchedule, ForceClosedStopsEverything) {
  PwmSchedule pwm(four_valves());
  pwm.set_duties(std::vector<double>{100, 100, 100, 100});
  pwm.start(0ns);
  for (int i = 0; i < 4; ++i) pwm.next_edge();
  EXPECT_EQ(pwm.current_mask(), 0b1111u);
  EXPECT_EQ(pwm.force_closed(), 0u);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(pwm.next_edge().valve_mask, 0u);
}

TEST(PwmSchedule, ThirtyTwoValves) {
  PwmConfig config;
  config.valve_count = 32;
  config.frequency_hz = 20.0;
  PwmSchedule pwm(config);
  pwm.set_duty(31, 100);
  pwm.start(0ns);
  std::uint32_t mask = 0;
  for (int i = 0; i < 40; ++i) mask = pwm.next_edge().valve_mask;
  EXPECT_EQ(mask, 1u << 31);
  EXPECT_EQ(pwm.phase_offset(31), nanoseconds(50ms) / 32);  // outer-first: valve 31 is second
}

TEST(PwmSchedule, RejectsBadConfig) {
  PwmConfig config = four_valves();
  config.frequency_hz = 0.5;
  EXPECT_THROW(PwmSchedule{config}, std::invalid_argument);
  config = four_valves();
  config.frequency_hz = 25;
  EXPECT_THROW(PwmSchedule{config}, std::invalid_argument);
  config = four_valves();
  config.valve_count = 33;
  EXPECT_THROW(PwmSchedule{config}, std::invalid_argument);
  config = four_valves();
  config.order = {0, 1, 1, 2};
  EXPECT_THROW(PwmSchedule{config}, std::invalid_argument);
  config = four_valves();
  config.order = {0, 1, 2};
  EXPECT_THROW(PwmSchedule{config}, std::invalid_argument);
  config = four_valves();
  config.min_on_time = 150ms;
  config.min_off_time = 60ms;
  EXPECT_THROW(PwmSchedule{config}, std::invalid_argument);
}

PwmConfig immediate_four_valves() {
  PwmConfig config = four_valves();
  config.immediate_start_stop = true;
  return config;
}

// Advances the schedule through every edge before `t`.
void advance_to(PwmSchedule& pwm, nanoseconds t) {
  while (pwm.peek_edge().time < t) pwm.next_edge();
}

// The next edge at which `valve` changes state (other valves' period starts are passed over).
PwmEdge next_change(PwmSchedule& pwm, std::size_t valve) {
  const std::uint32_t bit = 1u << valve;
  const std::uint32_t was = pwm.current_mask() & bit;
  PwmEdge edge = pwm.next_edge();
  while ((edge.valve_mask & bit) == was) edge = pwm.next_edge();
  return edge;
}

TEST(PwmSchedule, ImmediateModeStartsAClosedValveAtOnce) {
  PwmSchedule pwm(immediate_four_valves());
  pwm.start(0ns);
  advance_to(pwm, 360ms);
  // Valve 2's stagger slot is at 150 ms + k*200 ms: latched, it would open at 550 ms.
  pwm.set_duty(2, 50.0, 360ms);
  const PwmEdge opened = pwm.peek_edge();
  EXPECT_EQ(opened.time, 360ms);
  EXPECT_EQ(opened.valve_mask, 1u << 2);
  EXPECT_EQ(pwm.next_edge().time, 360ms);
  // The first period ends on the valve's own grid, at least T/2 on: 550 ms (190 ms long).
  const PwmEdge closed = next_change(pwm, 2);
  EXPECT_EQ(closed.time, 455ms) << "50 % of the stretched first period";
  EXPECT_EQ(closed.valve_mask, 0u);
  const PwmEdge next_period = next_change(pwm, 2);
  EXPECT_EQ(next_period.time, 550ms) << "later periods keep the valve's stagger slot";
  EXPECT_EQ(next_period.valve_mask, 1u << 2);
  EXPECT_EQ(next_change(pwm, 2).time, 650ms);
}

// Valves started at the same instant (Start, or the end of a weed-free stretch) must not stay in
// phase: after the first period each is back in its own slot, so the four open at four times.
TEST(PwmSchedule, ImmediateStartsTogetherFallBackIntoTheirStaggerSlots) {
  PwmSchedule pwm(immediate_four_valves());
  pwm.start(0ns);
  advance_to(pwm, 1010ms);
  const std::vector<double> half(4, 50.0);
  pwm.set_duties(half, 1010ms);
  const PwmEdge first = pwm.next_edge();
  EXPECT_EQ(first.time, 1010ms);
  EXPECT_EQ(first.valve_mask, 0b1111u) << "all open at once, on the ground";
  std::vector<nanoseconds> opened;
  for (PwmEdge edge = pwm.next_edge(), before = edge; edge.time < 1600ms;
       before = edge, edge = pwm.next_edge()) {
    for (std::size_t v = 0; v < 4; ++v)
      if (edge.time >= 1300ms && !(before.valve_mask >> v & 1u) && (edge.valve_mask >> v & 1u))
        opened.push_back(edge.time % 200ms);
  }
  std::sort(opened.begin(), opened.end());
  opened.erase(std::unique(opened.begin(), opened.end()), opened.end());
  EXPECT_EQ(opened, (std::vector<nanoseconds>{0ms, 50ms, 100ms, 150ms}));
  // Mean duty over the stretched/shortened first periods stays the requested 50 %.
  for (std::size_t v = 0; v < 4; ++v) EXPECT_EQ(pwm.valve_state(v).latched_duty_pct, 50.0);
}

TEST(PwmSchedule, ImmediateModeClosesAnOpenValveAtOnceButKeepsMinOnTime) {
  PwmConfig config = immediate_four_valves();
  config.min_on_time = 40ms;
  PwmSchedule pwm(config);
  pwm.set_duty(0, 50.0);
  pwm.start(0ns);
  EXPECT_EQ(pwm.next_edge().valve_mask, 1u);  // valve 0 opens at 0 until 100 ms
  pwm.set_duty(0, 0.0, 20ms);
  PwmEdge edge = pwm.next_edge();
  EXPECT_EQ(edge.time, 40ms) << "closed as soon as the minimum on-time allows";
  EXPECT_EQ(edge.valve_mask, 0u);
  // Later: open again, then close right away.
  advance_to(pwm, 300ms);        // the 200 ms period latched 0
  pwm.set_duty(0, 50.0, 300ms);  // min off-time 0: starts at once
  edge = pwm.next_edge();
  EXPECT_EQ(edge.time, 300ms);
  EXPECT_EQ(edge.valve_mask, 1u);
  advance_to(pwm, 345ms);  // open until 350 ms (the first period ends on the grid at 400 ms)
  pwm.set_duty(0, 0.0, 345ms);
  edge = pwm.next_edge();
  EXPECT_EQ(edge.time, 345ms);
  EXPECT_EQ(edge.valve_mask & 1u, 0u);
  EXPECT_EQ(pwm.mask_at(450ms), 0u) << "stays closed";
}

TEST(PwmSchedule, ImmediateStopOfAValveHeldOpenIgnoresItsLatestPeriodStart) {
  PwmConfig config = immediate_four_valves();
  config.min_on_time = 40ms;
  PwmSchedule pwm(config);
  pwm.set_duty(0, 100.0);
  pwm.start(0ns);
  EXPECT_EQ(pwm.next_edge().valve_mask & 1u, 1u);  // open since 0, periods 0, 200, 400 ms
  advance_to(pwm, 405ms);
  // The valve has been open for 405 ms: a stop 5 ms after its period start closes it now,
  // not 40 ms after that period start.
  pwm.set_duty(0, 0.0, 405ms);
  const PwmEdge edge = next_change(pwm, 0);
  EXPECT_EQ(edge.time, 405ms);
  EXPECT_EQ(edge.valve_mask & 1u, 0u);
}

TEST(PwmSchedule, ImmediateStartWaitsOnlyForTheMinimumOffTime) {
  PwmConfig config = immediate_four_valves();
  config.min_off_time = 60ms;
  PwmSchedule pwm(config);
  pwm.set_duty(0, 50.0);
  pwm.start(0ns);
  pwm.next_edge();              // opens at 0
  pwm.set_duty(0, 0.0, 100ms);  // during the pulse ...
  pwm.set_duty(0, 0.0, 10ms);   // ... closes at 10 ms
  EXPECT_EQ(pwm.next_edge().time, 10ms);
  advance_to(pwm, 200ms);
  pwm.next_edge();  // the 200 ms period start latches 0: closed all period
  pwm.set_duty(0, 50.0, 205ms);
  // Closed since 10 ms: min off-time long satisfied, so it opens at once.
  EXPECT_EQ(pwm.peek_edge().time, 205ms);
  pwm.next_edge();
  pwm.set_duty(0, 0.0, 230ms);
  EXPECT_EQ(pwm.next_edge().time, 230ms);
  pwm.set_duty(0, 0.0, 240ms);
  // Another valve's edge must not hide the off-time: request at 250 ms -> opens at 290 ms.
  pwm.set_duty(0, 50.0, 250ms);
  advance_to(pwm, 290ms);
  const PwmEdge reopened = pwm.next_edge();
  EXPECT_EQ(reopened.time, 290ms) << "closed at 230 ms + 60 ms minimum off-time";
  EXPECT_EQ(reopened.valve_mask, 1u);
}

TEST(PwmSchedule, LatchedModeStillWaitsForThePeriodStart) {
  PwmSchedule pwm(four_valves());
  pwm.start(0ns);
  advance_to(pwm, 360ms);
  pwm.set_duty(2, 50.0, 360ms);
  PwmEdge edge = pwm.next_edge();
  while (edge.valve_mask == 0) edge = pwm.next_edge();
  EXPECT_EQ(edge.time, 550ms);
  EXPECT_EQ(edge.valve_mask, 1u << 2);
}

TEST(PwmSchedule, PeekEdgeMatchesNextEdge) {
  PwmConfig config = immediate_four_valves();
  config.min_on_time = 10ms;
  PwmSchedule pwm(config);
  pwm.start(0ns);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> duty(0.0, 100.0);
  for (int i = 0; i < 2000; ++i) {
    if (i % 5 == 0) {
      const auto v = static_cast<std::size_t>(i / 5 % 4);
      pwm.set_duty(v, i % 3 == 0 ? 0.0 : duty(rng), pwm.last_edge_time() + 1ms);
    }
    const PwmEdge peeked = pwm.peek_edge();
    const nanoseconds before = pwm.last_edge_time();
    const PwmEdge edge = pwm.next_edge();
    ASSERT_EQ(peeked.time, edge.time);
    ASSERT_EQ(peeked.valve_mask, edge.valve_mask);
    ASSERT_GE(edge.time, before);
  }
}

}  // namespace
}  // namespace weedspray::control
