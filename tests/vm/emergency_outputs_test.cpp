// SPDX-License-Identifier: Apache-2.0
// The fatal-exit path on real kernel lines (gpio-sim): the bank's emergency write is a
// GPIOHANDLE_SET_LINE_VALUES ioctl on the line handle libgpiod holds, made without libgpiod.
// To see what a dying process wrote before the kernel releases its lines, the TEST process
// requests the bank and forks: the child shares the line handle, drives the valves open, and
// dies of a fatal signal; the parent's copy of the handle keeps the lines requested, so gpio-sim
// still shows the last value written - the handler's safe one, or "open" without it.
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <csignal>
#include <cstdint>
#include <stdexcept>
#include <thread>

#include "io/emergency_outputs.hpp"
#include "io/linux/gpio_output_bank.hpp"
#include "tests/vm/gpio_sim_chip.hpp"

namespace weedspray::io::hw {
namespace {

using vm_test::GpioSimChip;

// guest-init.sh names the output chip's lines valve0..valve3 pump buzzer lamp aux.
GpioOutputBankConfig bank_config(const std::string& chip, unsigned first, unsigned count,
                                 bool active_low) {
  GpioOutputBankConfig config;
  config.chip = chip;
  config.consumer = "vm-emergency-test";
  for (unsigned offset = first; offset < first + count; ++offset)
    config.lines.push_back({.name = "",
                            .offset = static_cast<int>(offset),
                            .active_low = active_low,
                            .safe_value = false});
  return config;
}

class EmergencyOutputsTest : public ::testing::Test {
 protected:
  void SetUp() override { EmergencyOutputs::clear(); }
  void TearDown() override { EmergencyOutputs::clear(); }
  GpioSimChip chip_{"weedspray-out"};
};

TEST_F(EmergencyOutputsTest, TheRawIoctlWritesEachBanksSafeValues) {
  GpioOutputBank valves(bank_config(chip_.chip_name(), 0, 4, false));
  GpioOutputBank pump(bank_config(chip_.chip_name(), 4, 1, true));  // active-low relay
  EmergencyWrite write;
  ASSERT_TRUE(valves.emergency_write(write)) << "the valves' line handle was not found";
  ASSERT_TRUE(EmergencyOutputs::add(write));
  ASSERT_TRUE(pump.emergency_write(write)) << "the pump's line handle was not found";
  ASSERT_TRUE(EmergencyOutputs::add(write));
  ASSERT_EQ(valves.write(0xF), 0);
  ASSERT_EQ(pump.write(1), 0);
  for (unsigned i = 0; i < 4; ++i) ASSERT_EQ(chip_.value(i), 1);
  ASSERT_EQ(chip_.value(4), 0) << "active-low pump on = low";

  EXPECT_EQ(EmergencyOutputs::trigger(), 0);
  for (unsigned i = 0; i < 4; ++i) EXPECT_EQ(chip_.value(i), 0) << "valve " << i;
  EXPECT_EQ(chip_.value(4), 1) << "pump relay off (high)";
}

enum class Death {
  kSignal,
  kEscapedException,
  // A second thread keeps writing the valves open through the bank, as the valve PWM thread
  // does on the other CPU, while the main thread dies of the signal.
  kSignalWhileAThreadWrites,
};

// Forks a child that shares the bank's handle, opens every valve, arms (or not) the handlers
// and dies as told; returns the child's wait status.
int open_valves_and_die(GpioOutputBank& valves, Death how, int signal, bool armed) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (valves.write(0xF) != 0) ::_exit(90);
    EmergencyWrite write;
    if (armed && !(valves.emergency_write(write) && EmergencyOutputs::add(write))) ::_exit(91);
    install_fatal_exit_handlers();
    switch (how) {
      case Death::kSignal:
        ::raise(signal);
        break;
      case Death::kEscapedException:
        std::thread([] { throw std::runtime_error("escaped from a thread"); }).join();
        break;
      case Death::kSignalWhileAThreadWrites: {
        std::atomic<int> writes{0};
        std::thread([&] {
          for (;;) {
            if (valves.write(0xF) != 0) ::_exit(93);
            writes.fetch_add(1);
          }
        }).detach();
        while (writes.load() < 50) std::this_thread::yield();
        ::raise(signal);
        break;
      }
    }
    ::_exit(92);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

TEST_F(EmergencyOutputsTest, EveryFatalSignalLeavesTheValvesClosed) {
  GpioOutputBank valves(bank_config(chip_.chip_name(), 0, 4, false));
  for (int signal : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL}) {
    const int status = open_valves_and_die(valves, Death::kSignal, signal, true);
    ASSERT_TRUE(WIFSIGNALED(status)) << "signal " << signal << " status " << status;
    EXPECT_EQ(WTERMSIG(status), signal);
    for (unsigned i = 0; i < 4; ++i) EXPECT_EQ(chip_.value(i), 0) << "signal " << signal;
  }
  // Unarmed, the same death leaves them open: the check above can fail.
  const int status = open_valves_and_die(valves, Death::kSignal, SIGSEGV, false);
  ASSERT_TRUE(WIFSIGNALED(status));
  for (unsigned i = 0; i < 4; ++i) EXPECT_EQ(chip_.value(i), 1) << "valve " << i;
}

// An exception escaping a thread: std::terminate's handler writes the lines safe and aborts.
TEST_F(EmergencyOutputsTest, AnEscapedExceptionLeavesTheValvesClosed) {
  GpioOutputBank valves(bank_config(chip_.chip_name(), 0, 4, false));
  const int status = open_valves_and_die(valves, Death::kEscapedException, 0, true);
  ASSERT_TRUE(WIFSIGNALED(status)) << "status " << status;
  EXPECT_EQ(WTERMSIG(status), SIGABRT);
  for (unsigned i = 0; i < 4; ++i) EXPECT_EQ(chip_.value(i), 0) << "valve " << i;
}

// After the handler's safe writes, no write of a thread still running may open a valve again
// before the process is gone (the bank's write passes the gate).
TEST_F(EmergencyOutputsTest, AThreadStillWritingCannotReopenAValve) {
  GpioOutputBank valves(bank_config(chip_.chip_name(), 0, 4, false));
  for (int signal : {SIGSEGV, SIGABRT}) {
    for (int death = 0; death < 20; ++death) {
      const int status =
          open_valves_and_die(valves, Death::kSignalWhileAThreadWrites, signal, true);
      ASSERT_TRUE(WIFSIGNALED(status)) << "signal " << signal << " status " << status;
      ASSERT_EQ(WTERMSIG(status), signal);
      for (unsigned i = 0; i < 4; ++i)
        ASSERT_EQ(chip_.value(i), 0) << "valve " << i << ", death " << death << " of " << signal;
    }
  }
}

}  // namespace
}  // namespace weedspray::io::hw
