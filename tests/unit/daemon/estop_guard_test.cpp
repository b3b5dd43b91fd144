// SPDX-License-Identifier: Apache-2.0
// The E-stop's reaction and latch on simulated outputs: the reaction writes valves and pump
// safe and records how long after the edge; the latch holds until reset() finds the circuit
// closed.
#include "daemon/sprayer/estop_guard.hpp"

#include <gtest/gtest.h>

#include "io/sim/manual_clock.hpp"
#include "io/sim/manual_estop_input.hpp"
#include "io/sim/memory_output_bank.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

// Outputs whose writes take `write_time` of the clock, so the reaction time is measurable.
class SlowBank final : public io::DigitalOutputBank {
 public:
  SlowBank(io::sim::ManualClock& clock, std::size_t lines, std::chrono::nanoseconds write_time)
      : clock_(clock), inner_(lines, 0, clock), write_time_(write_time) {}
  std::size_t size() const noexcept override { return inner_.size(); }
  int write(std::uint32_t mask) noexcept override {
    clock_.advance(write_time_);
    return inner_.write(mask);
  }
  int force_safe() noexcept override {
    clock_.advance(write_time_);
    return inner_.force_safe();
  }
  std::uint32_t safe_mask() const noexcept override { return 0; }
  std::uint32_t mask() const noexcept { return inner_.mask(); }

 private:
  io::sim::ManualClock& clock_;
  io::sim::MemoryOutputBank inner_;
  std::chrono::nanoseconds write_time_;
};

struct Machine {
  io::sim::ManualClock clock{10s};
  io::sim::ManualEstopInput input{clock};
  SlowBank valves{clock, 4, 300us};
  SlowBank pump{clock, 1, 200us};
  EstopGuard guard{clock, &input, &valves, &pump};
  Machine() {
    input.arm(guard.reaction());
    valves.write(0b1011);
    pump.write(1);
  }
};

TEST(EstopGuard, OpeningWritesValvesAndPumpSafeAndRecordsTheReactionTime) {
  Machine m;
  EXPECT_FALSE(m.guard.held().load());
  m.input.set_closed(false);
  EXPECT_EQ(m.valves.mask(), 0U);
  EXPECT_EQ(m.pump.mask(), 0U);
  EXPECT_TRUE(m.guard.held().load());
  const EstopStatus s = m.guard.status();
  EXPECT_TRUE(s.wired);
  EXPECT_FALSE(s.circuit_closed);
  EXPECT_TRUE(s.latched);
  EXPECT_EQ(s.trips, 1U);
  EXPECT_EQ(s.last_reaction, 500us) << "edge -> both safe writes done";
  EXPECT_EQ(s.max_reaction, 500us);
}

TEST(EstopGuard, StaysLatchedUntilTheCircuitIsClosedAndReset) {
  Machine m;
  m.input.set_closed(false);
  EXPECT_FALSE(m.guard.reset()) << "the circuit is still open";
  EXPECT_TRUE(m.guard.held().load());
  m.input.set_closed(true);
  EXPECT_TRUE(m.guard.held().load()) << "closing the circuit alone does not unlatch";
  EXPECT_TRUE(m.guard.status().circuit_closed);
  EXPECT_TRUE(m.guard.reset());
  EXPECT_FALSE(m.guard.held().load());
  EXPECT_FALSE(m.guard.status().latched);
}

// An opening between reset()'s check of the circuit and its unlatching wins: the input reads
// closed to reset(), but the trip count moved.
class OpensDuringReset final : public io::EstopInput {
 public:
  io::EstopSample sample() const noexcept override {
    if (guard != nullptr && open_on_read) {
      open_on_read = false;
      guard->trip(std::chrono::nanoseconds{0});
    }
    io::EstopSample s;
    s.circuit_closed = true;
    return s;
  }
  void arm(const io::EstopReaction&) override {}
  void disarm() noexcept override {}
  EstopGuard* guard = nullptr;
  mutable bool open_on_read = false;
};

TEST(EstopGuard, ATripRacingTheResetStandsLatched) {
  io::sim::ManualClock clock{1s};
  OpensDuringReset input;
  EstopGuard guard(clock, &input, nullptr, nullptr);
  input.guard = &guard;
  guard.trip(clock.now());
  input.open_on_read = true;
  EXPECT_FALSE(guard.reset());
  EXPECT_TRUE(guard.held().load());
  EXPECT_TRUE(guard.reset()) << "no trip this time";
}

TEST(EstopGuard, WithoutAnInputNothingLatches) {
  io::sim::ManualClock clock;
  EstopGuard guard(clock, nullptr, nullptr, nullptr);
  EXPECT_FALSE(guard.status().wired);
  EXPECT_TRUE(guard.status().circuit_closed);
  EXPECT_FALSE(guard.held().load());
  EXPECT_TRUE(guard.reset());
}

}  // namespace
}  // namespace weedspray::daemon
