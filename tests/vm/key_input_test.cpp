// SPDX-License-Identifier: Apache-2.0
// The debounced start/stop key (io::hw::GpioDigitalInput) on a gpio-sim line in a real kernel.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <stdexcept>
#include <thread>

#include "io/linux/gpio_digital_input.hpp"
#include "io/linux/monotonic_clock.hpp"
#include "tests/vm/gpio_sim_chip.hpp"

namespace weedspray::io::hw {
namespace {

using namespace std::chrono_literals;
using vm_test::GpioSimChip;

constexpr unsigned int kKeyOffset = 2;  // guest-init.sh: flow wheel key
constexpr auto kDebounce = 30ms;

DigitalInputSample wait_for_changes(const DigitalInput& input, std::uint64_t changes) {
  const auto deadline = monotonic_now() + std::chrono::nanoseconds(5s);
  DigitalInputSample sample = input.sample();
  while (sample.change_count < changes && monotonic_now() < deadline) {
    std::this_thread::sleep_for(1ms);
    sample = input.sample();
  }
  return sample;
}

class KeyInputTest : public ::testing::Test {
 protected:
  void SetUp() override { chip_.pull(kKeyOffset, false); }
  void TearDown() override { SetUp(); }
  GpioSimChip chip_{"weedspray-in"};
};

TEST_F(KeyInputTest, FollowsAHeldPressAndRelease) {
  GpioDigitalInput key({.chip = chip_.label(),
                        .line = {.name = "key"},
                        .debounce = kDebounce,
                        .consumer = "vm-key-test"});
  std::this_thread::sleep_for(2 * kDebounce);
  EXPECT_FALSE(key.sample().active);
  EXPECT_EQ(key.sample().change_count, 0U);

  const auto pressed_at = monotonic_now();
  chip_.pull(kKeyOffset, true);
  DigitalInputSample sample = wait_for_changes(key, 1);
  ASSERT_EQ(sample.change_count, 1U);
  EXPECT_TRUE(sample.active);
  EXPECT_GE(sample.time - pressed_at, kDebounce) << "accepted before the debounce time";

  chip_.pull(kKeyOffset, false);
  sample = wait_for_changes(key, 2);
  ASSERT_EQ(sample.change_count, 2U);
  EXPECT_FALSE(sample.active);
  EXPECT_EQ(sample.error_count, 0U);
}

TEST_F(KeyInputTest, IgnoresAGlitchShorterThanTheDebounceTime) {
  // Two back-to-back sysfs writes are microseconds apart, but the emulated CPU may be
  // descheduled by a busy host between them: a long debounce keeps the glitch a glitch.
  constexpr auto kLongDebounce = 300ms;
  GpioDigitalInput key({.chip = chip_.chip_name(),
                        .line = {.name = "", .offset = static_cast<int>(kKeyOffset)},
                        .debounce = kLongDebounce,
                        .consumer = "vm-key-test"});
  chip_.pull(kKeyOffset, true);
  chip_.pull(kKeyOffset, false);
  std::this_thread::sleep_for(2 * kLongDebounce);
  EXPECT_EQ(key.sample().change_count, 0U);
  EXPECT_FALSE(key.sample().active);
}

TEST_F(KeyInputTest, ActiveLowKeyReadsPressedWhenPulledDown) {
  GpioDigitalInput key({.chip = chip_.chip_name(),
                        .line = {.name = "key", .active_low = true},
                        .debounce = kDebounce,
                        .consumer = "vm-key-test"});
  // The line rests low (pull-down), i.e. pressed for an active-low key.
  std::this_thread::sleep_for(2 * kDebounce);
  EXPECT_TRUE(key.sample().active);
  chip_.pull(kKeyOffset, true);
  const DigitalInputSample sample = wait_for_changes(key, 1);
  EXPECT_FALSE(sample.active);
}

TEST_F(KeyInputTest, UnknownChipIsAClearError) {
  try {
    GpioDigitalInput key({.chip = "no-such-chip", .line = {.name = "key"}});
    ADD_FAILURE() << "no error for a missing chip";
  } catch (const std::runtime_error& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr("no-such-chip"));
  }
}

}  // namespace
}  // namespace weedspray::io::hw
