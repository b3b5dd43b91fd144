// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <chrono>
#include <vector>

#include "io/estop_input.hpp"
#include "io/sim/manual_clock.hpp"
#include "io/sim/manual_estop_input.hpp"

namespace weedspray::io {
namespace {

using namespace std::chrono_literals;
using std::chrono::nanoseconds;

TEST(NormallyClosedContact, TheFirstOpeningEdgeActsUndebounced) {
  NormallyClosedContact contact(50ms, true, 0ns);
  EXPECT_TRUE(contact.closed());
  EXPECT_TRUE(contact.feed(false, 10ms)) << "an opening acts on its first edge";
  EXPECT_FALSE(contact.closed());
  EXPECT_EQ(contact.changed_at(), 10ms);
  // The contact bounces: closed for 1 ms, open again. Each reopening acts again; the circuit
  // never counts as closed.
  EXPECT_FALSE(contact.feed(true, 11ms));
  EXPECT_FALSE(contact.settle(12ms));
  EXPECT_TRUE(contact.feed(false, 12ms));
  EXPECT_FALSE(contact.closed());
  EXPECT_FALSE(contact.feed(false, 13ms)) << "the same level again is no edge";
}

TEST(NormallyClosedContact, ClosingCountsOnlyAfterHoldingClosed) {
  NormallyClosedContact contact(50ms, false, 0ns);
  EXPECT_FALSE(contact.closed());
  EXPECT_FALSE(contact.feed(true, 100ms));
  EXPECT_TRUE(contact.pending());
  EXPECT_EQ(contact.pending_until(), 150ms);
  EXPECT_FALSE(contact.settle(149ms));
  EXPECT_FALSE(contact.closed());
  EXPECT_TRUE(contact.settle(150ms));
  EXPECT_TRUE(contact.closed());
  EXPECT_EQ(contact.changed_at(), 150ms);
  EXPECT_FALSE(contact.pending());
}

struct Recorder {
  std::vector<nanoseconds> edges;
  static void on_open(void* self, nanoseconds edge) noexcept {
    static_cast<Recorder*>(self)->edges.push_back(edge);
  }
  EstopReaction reaction() { return {&Recorder::on_open, this}; }
};

TEST(ManualEstopInput, OpeningRunsTheReactionAtOnceWithTheEdgeTime) {
  sim::ManualClock clock(1s);
  sim::ManualEstopInput input(clock);
  Recorder recorder;
  input.arm(recorder.reaction());
  EXPECT_TRUE(recorder.edges.empty()) << "a closed circuit runs nothing when armed";
  clock.advance(5ms);
  input.set_closed(false);
  ASSERT_EQ(recorder.edges.size(), 1U);
  EXPECT_EQ(recorder.edges[0], 1005ms);
  EXPECT_FALSE(input.sample().circuit_closed);
  EXPECT_EQ(input.sample().openings, 1U);
  input.set_closed(false);
  EXPECT_EQ(recorder.edges.size(), 1U) << "already open";
  input.set_closed(true);
  EXPECT_TRUE(input.sample().circuit_closed);
  EXPECT_EQ(recorder.edges.size(), 1U) << "closing runs nothing";
  input.disarm();
  input.set_closed(false);
  EXPECT_EQ(recorder.edges.size(), 1U) << "disarmed";
}

TEST(ManualEstopInput, ArmingWithTheCircuitOpenRunsTheReaction) {
  sim::ManualClock clock(2s);
  sim::ManualEstopInput input(clock, false);
  Recorder recorder;
  input.arm(recorder.reaction());
  ASSERT_EQ(recorder.edges.size(), 1U);
  EXPECT_EQ(recorder.edges[0], 2s);
}

}  // namespace
}  // namespace weedspray::io
