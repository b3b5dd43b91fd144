// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/output_write_watch.hpp"

#include <gtest/gtest.h>

#include <cerrno>

#include "daemon/supervision/alarms.hpp"

namespace weedspray::daemon {
namespace {

constexpr std::size_t at(OutputRole role) {
  return static_cast<std::size_t>(role);
}

OutputWriteWatch make_watch() {
  std::array<std::string, kOutputRoleCount> devices;
  devices[at(OutputRole::kPump)] = "gpiochip1 line 7 (pump)";
  return OutputWriteWatch(devices);
}

TEST(OutputWriteWatch, QuietWhileNothingFails) {
  OutputWriteWatch watch = make_watch();
  OutputWriteCounters counters;
  EXPECT_EQ(watch.update(counters), "");
  EXPECT_EQ(watch.update(counters), "");
}

TEST(OutputWriteWatch, NamesTheOutputAndCountsOnlyNewFailures) {
  OutputWriteWatch watch = make_watch();
  OutputWriteCounters counters;
  counters.failed_writes[at(OutputRole::kPump)] = 3;
  EXPECT_EQ(watch.update(counters), "pump relay (gpiochip1 line 7 (pump)): 3 failed write(s)");
  // The same count again: nothing new failed.
  EXPECT_EQ(watch.update(counters), "");
  counters.failed_writes[at(OutputRole::kValves)] = 1;
  EXPECT_EQ(watch.update(counters), "valves: 1 failed write(s)");
}

TEST(OutputWriteWatch, AFailingSafeWriteStaysPresentUntilWritten) {
  OutputWriteWatch watch = make_watch();
  OutputWriteCounters counters;
  counters.unsafe_error[at(OutputRole::kReturnValve)] = EIO;
  const std::string message = watch.update(counters);
  EXPECT_EQ(message, "return valve DAC: safe value not written: Input/output error");
  EXPECT_EQ(watch.update(counters), message);
  counters.unsafe_error[at(OutputRole::kReturnValve)] = 0;
  EXPECT_EQ(watch.update(counters), "");
}

TEST(OutputWriteWatch, TheAlarmIsAFaultRaisedAtOnce) {
  AlarmEvaluator alarms{AlarmsSection{}};
  AlarmInputs in;
  in.pressure_valid = true;
  in.output_write_failed = true;
  EXPECT_TRUE(alarms.evaluate(in) & alarm_bit(AlarmId::kOutputWriteFailed));
  EXPECT_TRUE(alarms.fault_latched());
  EXPECT_EQ(alarm_name(AlarmId::kOutputWriteFailed), "output_write_failed");
}

}  // namespace
}  // namespace weedspray::daemon
