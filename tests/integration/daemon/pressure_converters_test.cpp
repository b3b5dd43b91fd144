// SPDX-License-Identifier: Apache-2.0
// The daemon's pressure converters chosen by configuration ([adc]/[dac] source = "modbus") and
// driven by the converters' thread (io::AnalogIoWorker), against an independent Modbus RTU peer
// (Debian's pymodbus over a socat pty pair).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <thread>

#include "daemon/backends/backends.hpp"
#include "io/analog_io_worker.hpp"
#include "io/linux/modbus_analog.hpp"
#include "io/linux/monotonic_clock.hpp"
#include "io/signal_conversion.hpp"
#include "tests/integration/io/modbus_peer.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

constexpr int kSlave = 7;
constexpr int kPressureRegister = 2;  // input register with the sensor voltage in mV
constexpr int kValveRegister = 5;     // holding register the valve voltage goes to, in mV

class PressureConverters : public test::ModbusPeerTest {
 protected:
  Config modbus_config() const {
    Config config = default_config();
    config.adc.source = "modbus";
    config.adc.modbus_slave_id = kSlave;
    config.adc.modbus_register = kPressureRegister;
    config.adc.modbus_register_type = "input";
    config.adc.modbus_volts_per_count = 0.001;
    config.dac.source = "modbus";
    config.dac.modbus_slave_id = kSlave;
    config.dac.modbus_register = kValveRegister;
    config.dac.modbus_volts_per_count = 0.001;
    config.dac.full_scale_v = 10.0;  // a 0-10 V output module drives the valve directly
    config.analog_modbus.device = master_.string();
    config.analog_modbus.timeout_s = 0.3;
    return config;
  }

  // The valve register as the peer holds it, read back over the bus.
  double valve_register_volts() {
    io::hw::ModbusAnalogInput readback(
        {{master_.string(), 115200, 'N', 8, 1, kSlave, 300ms}, kValveRegister, false, 0.001},
        clock_);
    const io::AnalogSample s = readback.read();
    EXPECT_TRUE(s.ok) << readback.last_error();
    return s.volts;
  }

  // pymodbus needs a moment after "ready" before it serves.
  void wait_until_serving() {
    io::hw::ModbusAnalogInput probe(
        {{master_.string(), 115200, 'N', 8, 1, kSlave, 300ms}, kPressureRegister, true, 0.001},
        clock_);
    ASSERT_TRUE(test::wait_for([&] { return probe.read().ok; }, 10s))
        << probe.last_error() << "\nslave: " << slave_log();
  }

  io::hw::MonotonicClock clock_;
};

TEST_F(PressureConverters, ModbusModulesFromTheConfigurationReadAndWriteThroughTheWorker) {
  // 1.234 V across the 165 ohm shunt: 7.48 mA, a quarter of the sensor's range.
  start_slave({"normal", std::to_string(kSlave), std::to_string(kPressureRegister) + "=1234",
               std::to_string(kValveRegister) + "=4321"});
  wait_until_serving();
  const Config config = modbus_config();
  daemon::PressureConverters converters = make_hw_pressure_converters(config, clock_);
  ASSERT_TRUE(converters.adc && converters.dac);
  const double safe_volts = io::dac_volts_from_valve_opening(1.0, converters.drive);
  EXPECT_NEAR(valve_register_volts(), safe_volts, 1e-9) << "the DAC starts at its safe value";

  io::AnalogIoTiming timing;
  timing.period = 10ms;
  io::AnalogIoWorker worker(*converters.adc, *converters.dac, clock_, timing);
  worker.command(2.5);
  {
    std::jthread thread([&](std::stop_token stop) { worker.run(stop, clock_.now() + 10ms); });
    ASSERT_TRUE(test::wait_for([&] { return worker.stats().reads >= 20; }, 5s))
        << "reads: " << worker.stats().reads;
  }
  io::AnalogSample sample;
  ASSERT_TRUE(worker.try_latest_sample(sample));
  ASSERT_TRUE(sample.ok);
  EXPECT_NEAR(sample.volts, 1.234, 1e-9);
  const io::PressureReading reading =
      io::pressure_from_sensor_volts(sample.volts, converters.sensor);
  EXPECT_TRUE(reading.ok());
  EXPECT_NEAR(reading.current_ma, 1.234 / 165.0 * 1000.0, 1e-9);
  const io::AnalogIoStats stats = worker.stats();
  EXPECT_EQ(stats.dac_errors, 0U);
  EXPECT_EQ(stats.writes, 1U) << "one command, written once";
  EXPECT_NEAR(valve_register_volts(), 2.5, 1e-9);
  // A Modbus round trip over the pty is far longer than the minimum lead: the lead adapted.
  EXPECT_GT(stats.lead, timing.min_lead);
  EXPECT_LE(stats.lead, timing.period / 2);
  std::printf("modbus converters over a pty: %llu reads, max read %.0f us, lead %.0f us\n",
              static_cast<unsigned long long>(stats.reads), stats.max_read_time.count() / 1e3,
              stats.lead.count() / 1e3);

  converters.dac->force_safe();
  EXPECT_NEAR(valve_register_volts(), safe_volts, 1e-9);
}

TEST_F(PressureConverters, ASilentOutputModuleStopsTheStartWithItsDeviceNamed) {
  start_slave({"silent"});
  Config config = modbus_config();
  config.analog_modbus.timeout_s = 0.1;
  try {
    (void)make_hw_pressure_converters(config, clock_);
    FAIL() << "a DAC module that cannot be made safe must stop the start";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(master_.string()), std::string::npos) << what;
    EXPECT_NE(what.find("safe value"), std::string::npos) << what;
  }
}

TEST(PressureConvertersConfig, MissingSerialPortIsNamed) {
  Config config = default_config();
  config.adc.source = "modbus";
  config.analog_modbus.device = "/dev/ttyNOPE-weedspray";
  io::hw::MonotonicClock clock;
  try {
    (void)make_hw_pressure_converters(config, clock);
    FAIL() << "expected an error for a missing serial port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/ttyNOPE-weedspray"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace weedspray::daemon
