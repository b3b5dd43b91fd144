// SPDX-License-Identifier: Apache-2.0
// The Modbus tank level reader and analog modules against independent peers: Debian's pymodbus
// RTU server and misbehaving slaves, over a socat pty pair (tests/integration/io/modbus_peer.hpp).
#include "io/linux/modbus_tank_level.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "io/linux/modbus_analog.hpp"
#include "io/linux/monotonic_clock.hpp"
#include "tests/integration/io/modbus_peer.hpp"

namespace weedspray::io::hw {
namespace {

using namespace std::chrono_literals;

class ModbusPeer : public test::ModbusPeerTest {
 protected:
  ModbusTankLevelConfig config(int register_address = 0) const {
    ModbusTankLevelConfig c;
    c.device = master_.string();
    c.baud = 9600;
    c.slave_id = 7;
    c.register_address = register_address;
    c.percent_per_count = 0.1;
    c.response_timeout = 300ms;
    return c;
  }

  MonotonicClock clock_;
};

// pymodbus needs a moment after "ready" before it serves: the first good read may take a few.
TankLevelSample first_ok(ModbusTankLevel& sensor, int attempts) {
  TankLevelSample s;
  for (int i = 0; i < attempts; ++i) {
    s = sensor.read();
    if (s.ok) break;
  }
  return s;
}

TEST_F(ModbusPeer, ReadsTheLevelFromAPymodbusSlave) {
  start_slave({"normal", "7", "0=523", "1=2000"});
  ModbusTankLevel sensor(config(0), clock_);
  const TankLevelSample s = first_ok(sensor, 20);
  ASSERT_TRUE(s.ok) << sensor.last_error() << "\nslave: " << slave_log();
  EXPECT_NEAR(s.level_pct, 52.3, 1e-9);
  EXPECT_GT(s.time.count(), 0);
  for (int i = 0; i < 5; ++i) {
    const TankLevelSample again = sensor.read();
    EXPECT_TRUE(again.ok) << sensor.last_error();
    EXPECT_NEAR(again.level_pct, 52.3, 1e-9);
  }
  // Input registers hold the same values in this peer.
  ModbusTankLevelConfig input = config(0);
  input.register_type = ModbusRegisterType::kInput;
  ModbusTankLevel input_sensor(input, clock_);
  const TankLevelSample in = first_ok(input_sensor, 5);
  ASSERT_TRUE(in.ok) << input_sensor.last_error();
  EXPECT_NEAR(in.level_pct, 52.3, 1e-9);
}

TEST_F(ModbusPeer, OutOfRangeLevelIsInvalidNotALevel) {
  start_slave({"normal", "7", "0=523", "1=2000"});
  ModbusTankLevel good(config(0), clock_);
  ASSERT_TRUE(first_ok(good, 20).ok) << good.last_error();
  ModbusTankLevel sensor(config(1), clock_);  // 2000 * 0.1 = 200 % > 100 %
  const TankLevelSample s = sensor.read();
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.invalid_responses, 1U);
  EXPECT_NE(sensor.last_error().find("out of range"), std::string::npos) << sensor.last_error();
}

TEST_F(ModbusPeer, WrongSlaveIdTimesOut) {
  start_slave({"normal", "7", "0=523"});
  ModbusTankLevelConfig c = config(0);
  c.slave_id = 9;  // nobody answers for 9
  ModbusTankLevel sensor(c, clock_);
  const TankLevelSample s = sensor.read();
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.timeouts, 1U) << sensor.last_error();
}

TEST_F(ModbusPeer, SilentSlaveCountsTimeoutsWithoutHanging) {
  start_slave({"silent"});
  ModbusTankLevel sensor(config(0), clock_);
  const auto t0 = std::chrono::steady_clock::now();
  TankLevelSample s;
  for (int i = 0; i < 3; ++i) s = sensor.read();
  const auto elapsed = std::chrono::steady_clock::now() - t0;
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.reads, 3U);
  EXPECT_EQ(s.timeouts, 3U) << sensor.last_error();
  EXPECT_NE(sensor.last_error().find("timed out"), std::string::npos) << sensor.last_error();
  // Each read is bounded by the 300 ms response timeout (plus libmodbus's recovery wait).
  EXPECT_LT(elapsed, 3s);
}

TEST_F(ModbusPeer, BadCrcAnswersAreCountedAsCrcErrors) {
  start_slave({"badcrc", "7"});
  ModbusTankLevel sensor(config(0), clock_);
  TankLevelSample s;
  for (int i = 0; i < 3; ++i) s = sensor.read();
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.crc_errors, 3U) << sensor.last_error() << " timeouts " << s.timeouts << " invalid "
                              << s.invalid_responses;
}

TEST_F(ModbusPeer, JunkAnswersAreErrorsNeverALevel) {
  start_slave({"junk"});
  ModbusTankLevel sensor(config(0), clock_);
  const auto t0 = std::chrono::steady_clock::now();
  TankLevelSample s;
  for (int i = 0; i < 10; ++i) {
    s = sensor.read();
    EXPECT_FALSE(s.ok) << "junk decoded as level " << s.level_pct;
  }
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 15s);
  EXPECT_EQ(s.reads, 10U);
  EXPECT_EQ(s.timeouts + s.crc_errors + s.invalid_responses + s.other_errors, 10U);
  EXPECT_FALSE(sensor.last_error().empty());
}

TEST_F(ModbusPeer, RecoversWhenTheSlaveComesBack) {
  ModbusTankLevel sensor(config(0), clock_);
  EXPECT_FALSE(sensor.read().ok) << "no slave yet";
  start_slave({"normal", "7", "0=640"});
  const TankLevelSample s = first_ok(sensor, 20);
  ASSERT_TRUE(s.ok) << sensor.last_error();
  EXPECT_NEAR(s.level_pct, 64.0, 1e-9);
  EXPECT_GE(s.timeouts, 1U);
}

TEST_F(ModbusPeer, AnalogModuleInputAndOutputRoundTrip) {
  start_slave({"normal", "7", "0=523", "2=1234"});
  ModbusTankLevel probe(config(0), clock_);  // waits until the peer serves
  ASSERT_TRUE(first_ok(probe, 20).ok) << probe.last_error();

  const ModbusRtuSettings port{master_.string(), 9600, 'N', 8, 1, 7, 300ms};
  ModbusAnalogInput adc({port, 2, true, 0.001}, clock_);
  const AnalogSample in = adc.read();
  ASSERT_TRUE(in.ok) << adc.last_error();
  EXPECT_NEAR(in.volts, 1.234, 1e-9);

  {
    ModbusAnalogOutput dac({port, 5, 0.001, 10.0, 0.5, {}});  // writes the safe 0.5 V at start
    ModbusAnalogInput readback({port, 5, false, 0.001}, clock_);
    EXPECT_NEAR(readback.read().volts, 0.5, 1e-9);
    EXPECT_EQ(dac.write(2.5), 0);
    EXPECT_NEAR(readback.read().volts, 2.5, 1e-9);
    EXPECT_EQ(dac.write(99.0), 0);
    EXPECT_NEAR(readback.read().volts, 10.0, 1e-9) << "clamped to full scale";
  }
  ModbusAnalogInput readback({port, 5, false, 0.001}, clock_);
  EXPECT_NEAR(readback.read().volts, 0.5, 1e-9) << "destructor forces safe";
}

// A module with a communication watchdog gets the safe value and the timeout in its own
// registers before the output is used, so it goes safe by itself when the daemon falls silent.
TEST_F(ModbusPeer, AnalogOutputArmsTheModulesCommunicationWatchdog) {
  start_slave({"normal", "7", "0=523"});
  ModbusTankLevel probe(config(0), clock_);  // waits until the peer serves
  ASSERT_TRUE(first_ok(probe, 20).ok) << probe.last_error();
  const ModbusRtuSettings port{master_.string(), 9600, 'N', 8, 1, 7, 300ms};
  ModbusAnalogOutputConfig with_watchdog{port, 5, 0.001, 10.0, 0.5, {}};
  with_watchdog.watchdog = {
      .timeout_register = 20, .timeout_counts = 500, .timeout = 500ms, .safe_value_register = 21};
  ModbusAnalogOutput dac(with_watchdog);
  EXPECT_EQ(dac.rewrite_within(), std::chrono::nanoseconds(500ms) / 3);
  ModbusAnalogInput timeout({port, 20, false, 1.0}, clock_);
  ModbusAnalogInput safe_value({port, 21, false, 0.001}, clock_);
  EXPECT_DOUBLE_EQ(timeout.read().volts, 500.0);
  EXPECT_NEAR(safe_value.read().volts, 0.5, 1e-9);

  ModbusAnalogOutput plain({port, 5, 0.001, 10.0, 0.5, {}});
  EXPECT_EQ(plain.rewrite_within(), std::chrono::nanoseconds::zero()) << "no watchdog, no rewrite";
}

TEST_F(ModbusPeer, AnalogInputCountsErrorsOnASilentModule) {
  start_slave({"silent"});
  ModbusAnalogInput adc({{master_.string(), 9600, 'N', 8, 1, 7, 200ms}, 0, true, 0.001}, clock_);
  AnalogSample s = adc.read();
  s = adc.read();
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.error_count, 2U);
}

TEST(ModbusTankLevelConfig, ClearErrorsForBadDeviceAndSettings) {
  MonotonicClock clock;
  ModbusTankLevelConfig c;
  c.device = "/dev/ttyNOPE-weedspray";
  try {
    ModbusTankLevel sensor(c, clock);
    FAIL() << "expected an error for a missing serial port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/ttyNOPE-weedspray"), std::string::npos) << e.what();
  }
  c.parity = 'X';
  try {
    ModbusTankLevel sensor(c, clock);
    FAIL() << "expected an error for parity X";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("parity"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace weedspray::io::hw
