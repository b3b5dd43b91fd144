// SPDX-License-Identifier: Apache-2.0
// The valve bank (io::hw::GpioOutputBank) driving gpio-sim lines in a real kernel: what the
// lines physically show is read back through gpio-sim's sysfs, outside libgpiod.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/linux/gpio_lines.hpp"
#include "io/linux/gpio_output_bank.hpp"
#include "tests/vm/gpio_sim_chip.hpp"

namespace weedspray::io::hw {
namespace {

using vm_test::GpioSimChip;

// guest-init.sh names the output chip's lines valve0 valve1 valve2 valve3 pump buzzer lamp aux.
constexpr unsigned int kValveCount = 4;
constexpr unsigned int kPumpOffset = 4;

// Four active-high valves and an active-low pump relay, all safe = off (logical 0).
GpioOutputBankConfig valves_and_pump_by_offset(const std::string& chip) {
  GpioOutputBankConfig config;
  config.chip = chip;
  config.consumer = "vm-valve-test";
  for (unsigned int offset = 0; offset < kValveCount; ++offset)
    config.lines.push_back({.name = "", .offset = static_cast<int>(offset)});
  config.lines.push_back({.name = "", .offset = static_cast<int>(kPumpOffset), .active_low = true});
  return config;
}

// The physical level line i of the bank above must show for a logical mask.
int expected_level(unsigned int bank_index, std::uint32_t mask) {
  const bool on = (mask >> bank_index) & 1U;
  return bank_index == kPumpOffset ? !on : on;
}

void expect_lines_show(const GpioSimChip& chip, std::uint32_t mask) {
  for (unsigned int i = 0; i <= kPumpOffset; ++i)
    EXPECT_EQ(chip.value(i), expected_level(i, mask))
        << "line " << i << ", mask 0x" << std::hex << mask;
}

class ValveBankTest : public ::testing::Test {
 protected:
  GpioSimChip chip_{"weedspray-out"};
};

TEST_F(ValveBankTest, StartsSafeFollowsEveryMaskAndForcesSafe) {
  GpioOutputBank bank(valves_and_pump_by_offset(chip_.device_path()));
  ASSERT_EQ(bank.size(), 5U);
  EXPECT_EQ(bank.safe_mask(), 0U);
  EXPECT_EQ(bank.chip_name(), chip_.chip_name());
  // Safe from the request on: valves low, the active-low pump relay high (= off).
  expect_lines_show(chip_, 0);

  for (std::uint32_t mask = 0; mask < (1U << 5); ++mask) {
    ASSERT_EQ(bank.write(mask), 0) << "mask 0x" << std::hex << mask;
    expect_lines_show(chip_, mask);
  }
  ASSERT_EQ(bank.write(0x1F), 0);
  bank.force_safe();
  expect_lines_show(chip_, 0);
}

TEST_F(ValveBankTest, LeavesLinesOutsideTheBankAlone) {
  GpioOutputBank bank(valves_and_pump_by_offset(chip_.chip_name()));
  ASSERT_EQ(bank.write(0x1F), 0);
  for (unsigned int offset = kPumpOffset + 1; offset < 8; ++offset)
    EXPECT_EQ(chip_.value(offset), 0) << "line " << offset << " is not part of the bank";
}

TEST_F(ValveBankTest, FindsLinesByNameWithoutAChip) {
  GpioOutputBankConfig config;
  config.consumer = "vm-valve-test";
  // Deliberately out of offset order: bit i is the i-th configured line, not offset i.
  config.lines = {{.name = "pump", .active_low = true}, {.name = "valve3"}, {.name = "valve0"}};
  GpioOutputBank bank(config);
  EXPECT_EQ(bank.chip_name(), chip_.chip_name());
  EXPECT_THAT(bank.offsets(), ::testing::ElementsAre(4U, 3U, 0U));
  EXPECT_EQ(chip_.value(4), 1) << "pump must start off (active-low high)";

  ASSERT_EQ(bank.write(0b001), 0);  // pump on
  EXPECT_EQ(chip_.value(4), 0);
  EXPECT_EQ(chip_.value(3), 0);
  EXPECT_EQ(chip_.value(0), 0);
  ASSERT_EQ(bank.write(0b110), 0);  // pump off, valve3 and valve0 on
  EXPECT_EQ(chip_.value(4), 1);
  EXPECT_EQ(chip_.value(3), 1);
  EXPECT_EQ(chip_.value(0), 1);
  bank.force_safe();
  EXPECT_EQ(chip_.value(4), 1);
  EXPECT_EQ(chip_.value(3), 0);
  EXPECT_EQ(chip_.value(0), 0);
}

TEST_F(ValveBankTest, FindsTheChipByLabel) {
  GpioOutputBank bank(valves_and_pump_by_offset(chip_.label()));
  EXPECT_EQ(bank.chip_name(), chip_.chip_name());
  ASSERT_EQ(bank.write(0b00010), 0);
  expect_lines_show(chip_, 0b00010);
}

TEST_F(ValveBankTest, RequestsASafeOnLineHigh) {
  GpioOutputBankConfig config;
  config.chip = chip_.chip_name();
  config.consumer = "vm-valve-test";
  config.lines = {{.name = "lamp", .safe_value = true}};  // e.g. a "fault" lamp
  GpioOutputBank bank(config);
  EXPECT_EQ(bank.safe_mask(), 1U);
  EXPECT_EQ(chip_.value(6), 1);
  ASSERT_EQ(bank.write(0), 0);
  EXPECT_EQ(chip_.value(6), 0);
  bank.force_safe();
  EXPECT_EQ(chip_.value(6), 1);
}

// Errors must name what is wrong so the operator can fix the configuration.
void expect_error_mentions(const GpioOutputBankConfig& config, const std::string& needle) {
  try {
    GpioOutputBank bank(config);
    ADD_FAILURE() << "no error; expected one mentioning '" << needle << "'";
  } catch (const std::runtime_error& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr(needle));
  }
}

TEST_F(ValveBankTest, UnknownLineNameIsAClearError) {
  GpioOutputBankConfig config;
  config.lines = {{.name = "valve0"}, {.name = "valve-nonexistent"}};
  expect_error_mentions(config, "valve-nonexistent");
}

TEST_F(ValveBankTest, UnknownChipIsAClearError) {
  expect_error_mentions(valves_and_pump_by_offset("gpiochip-nonexistent"), "gpiochip-nonexistent");
}

TEST_F(ValveBankTest, OffsetBeyondTheChipIsAClearError) {
  GpioOutputBankConfig config = valves_and_pump_by_offset(chip_.chip_name());
  config.lines.push_back({.name = "", .offset = 42});
  expect_error_mentions(config, "42");
}

TEST_F(ValveBankTest, BusyLineIsAClearErrorAndTheHolderKeepsDriving) {
  GpioOutputBank holder(valves_and_pump_by_offset(chip_.chip_name()));
  ASSERT_EQ(holder.write(0b00001), 0);
  GpioOutputBankConfig config;
  config.chip = chip_.chip_name();
  config.lines = {{.name = "valve0"}};
  expect_error_mentions(config, "valve0");
  // Its own kind: the exit watcher retries only a busy line.
  EXPECT_THROW(GpioOutputBank{config}, GpioLineBusy);
  EXPECT_EQ(chip_.value(0), 1);
}

}  // namespace
}  // namespace weedspray::io::hw
