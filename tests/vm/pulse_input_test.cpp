// SPDX-License-Identifier: Apache-2.0
// The flow/wheel pulse counter (io::hw::GpioPulseInput) on gpio-sim lines in a real kernel:
// pulses are made from outside libgpiod by switching the simulated pull in sysfs.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include "io/linux/gpio_pulse_input.hpp"
#include "io/linux/monotonic_clock.hpp"
#include "tests/vm/gpio_sim_chip.hpp"

namespace weedspray::io::hw {
namespace {

using namespace std::chrono_literals;
using vm_test::GpioSimChip;

// guest-init.sh names the input chip's lines flow wheel key.
constexpr unsigned int kFlowOffset = 0;
constexpr unsigned int kWheelOffset = 1;

// Waits until the counter reaches `count` (or `timeout` passes) and returns the snapshot.
PulseSnapshot wait_for_count(const PulseInput& input, std::uint64_t count,
                             std::chrono::nanoseconds timeout = 5s) {
  const auto deadline = monotonic_now() + timeout;
  PulseSnapshot snapshot = input.snapshot();
  while (snapshot.count < count && monotonic_now() < deadline) {
    std::this_thread::sleep_for(200us);
    snapshot = input.snapshot();
  }
  return snapshot;
}

class PulseInputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    chip_.pull(kFlowOffset, false);
    chip_.pull(kWheelOffset, false);
  }
  void TearDown() override { SetUp(); }

  GpioSimChip chip_{"weedspray-in"};
};

// gpio-sim raises its interrupt through irq_work and the uAPI v1 handler is threaded: two
// edges made before that thread runs reach user space as ONE event (it reads the level when it
// runs). A real flow meter is far slower than sysfs writes, so every edge is given time to be
// delivered: each rising edge until it is counted, each falling edge kSettle.
constexpr auto kSettle = 3ms;

TEST_F(PulseInputTest, CountsAThousandPulsesExactlyWithKernelTimestamps) {
  constexpr int kPulses = 1000;
  GpioPulseInput flow({.chip = chip_.label(),
                       .line = {.name = "flow"},
                       .counted_edge = PulseEdge::kRising,
                       .consumer = "vm-pulse-test"});
  const auto started = monotonic_now();
  std::this_thread::sleep_for(20ms);
  EXPECT_EQ(flow.snapshot().count, 0U) << "no edge yet";

  std::chrono::nanoseconds previous_edge{0};
  for (int made = 1; made <= kPulses; ++made) {
    const auto before_rise = monotonic_now();
    chip_.pull(kFlowOffset, true);
    const PulseSnapshot snapshot = wait_for_count(flow, static_cast<std::uint64_t>(made));
    ASSERT_EQ(snapshot.count, static_cast<std::uint64_t>(made)) << "pulse " << made;
    // The edge's kernel timestamp lies between the write and now, on CLOCK_MONOTONIC.
    ASSERT_GE(snapshot.last_edge_time, before_rise) << "pulse " << made;
    ASSERT_LE(snapshot.last_edge_time, monotonic_now()) << "pulse " << made;
    ASSERT_GT(snapshot.last_edge_time, previous_edge) << "pulse " << made;
    previous_edge = snapshot.last_edge_time;
    chip_.pull(kFlowOffset, false);
    std::this_thread::sleep_for(kSettle);
  }
  std::this_thread::sleep_for(100ms);
  const PulseSnapshot final_snapshot = flow.snapshot();
  EXPECT_EQ(final_snapshot.count, static_cast<std::uint64_t>(kPulses)) << "no extra edges";
  EXPECT_EQ(final_snapshot.error_count, 0U);
  EXPECT_EQ(final_snapshot.overflow_count, 0U);
  EXPECT_GT(final_snapshot.last_edge_time, started);
}

TEST_F(PulseInputTest, CountsFallingEdgesOnTheWheelByOffset) {
  constexpr int kPulses = 200;
  GpioPulseInput wheel({.chip = chip_.chip_name(),
                        .line = {.name = "", .offset = static_cast<int>(kWheelOffset)},
                        .counted_edge = PulseEdge::kFalling,
                        .consumer = "vm-pulse-test"});
  for (int made = 1; made <= kPulses; ++made) {
    chip_.pull(kWheelOffset, true);
    std::this_thread::sleep_for(kSettle);
    // A rising edge alone must not count.
    EXPECT_EQ(wheel.snapshot().count, static_cast<std::uint64_t>(made - 1));
    const auto before_fall = monotonic_now();
    chip_.pull(kWheelOffset, false);
    const PulseSnapshot snapshot = wait_for_count(wheel, static_cast<std::uint64_t>(made));
    ASSERT_EQ(snapshot.count, static_cast<std::uint64_t>(made));
    EXPECT_GE(snapshot.last_edge_time, before_fall);
  }
  EXPECT_EQ(wheel.snapshot().overflow_count, 0U);
}

TEST_F(PulseInputTest, ActiveLowCountsThePhysicalFallAsARisingEdge) {
  GpioPulseInput flow({.chip = chip_.chip_name(),
                       .line = {.name = "flow", .active_low = true},
                       .counted_edge = PulseEdge::kRising,
                       .consumer = "vm-pulse-test"});
  chip_.pull(kFlowOffset, true);  // logical fall
  std::this_thread::sleep_for(20ms);
  EXPECT_EQ(flow.snapshot().count, 0U);
  chip_.pull(kFlowOffset, false);  // logical rise
  EXPECT_EQ(wait_for_count(flow, 1).count, 1U);
}

TEST_F(PulseInputTest, UnknownLineIsAClearError) {
  try {
    GpioPulseInput input({.chip = "", .line = {.name = "no-such-flow-line"}});
    ADD_FAILURE() << "no error for a missing line";
  } catch (const std::runtime_error& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr("no-such-flow-line"));
  }
}

}  // namespace
}  // namespace weedspray::io::hw
