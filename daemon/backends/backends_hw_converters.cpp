// SPDX-License-Identifier: Apache-2.0
// The pressure ADC and return-valve DAC of the board: Linux IIO devices (e.g. ADS1115 and
// MCP4725 on a Pi) or Modbus RTU analog modules on their own RS-485 bus ([analog_modbus]).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "daemon/backends/backends.hpp"
#include "io/linux/iio_analog.hpp"
#include "io/linux/modbus_analog.hpp"

namespace weedspray::daemon {
namespace {

io::hw::ModbusRtuSettings analog_bus(const AnalogModbusSection& bus, int slave_id) {
  io::hw::ModbusRtuSettings port;
  port.device = bus.device;
  port.baud = bus.baud;
  port.parity = bus.parity.front();
  port.slave_id = slave_id;
  port.response_timeout = std::chrono::milliseconds(static_cast<int>(bus.timeout_s * 1000));
  return port;
}

std::shared_ptr<io::AnalogInput> make_adc(const Config& config, const io::Clock& clock) {
  if (config.adc.source == "modbus") {
    io::hw::ModbusAnalogInputConfig adc;
    adc.port = analog_bus(config.analog_modbus, config.adc.modbus_slave_id);
    adc.register_address = config.adc.modbus_register;
    adc.input_register = config.adc.modbus_register_type == "input";
    adc.volts_per_count = config.adc.modbus_volts_per_count;
    return std::make_shared<io::hw::ModbusAnalogInput>(adc, clock);
  }
  io::hw::IioChannelConfig adc;
  adc.device = config.adc.iio_device;
  adc.channel = config.adc.pressure_channel;
  adc.scale_mv_override = config.adc.iio_scale_mv;
  return std::make_shared<io::hw::IioAnalogInput>(adc, clock);
}

std::shared_ptr<io::AnalogOutput> make_dac(const Config& config, double safe_volts) {
  if (config.dac.source == "modbus") {
    io::hw::ModbusAnalogOutputConfig dac;
    dac.port = analog_bus(config.analog_modbus, config.dac.modbus_slave_id);
    dac.register_address = config.dac.modbus_register;
    dac.volts_per_count = config.dac.modbus_volts_per_count;
    dac.full_scale_volts = config.dac.full_scale_v;
    dac.safe_volts = safe_volts;
    dac.watchdog.timeout_register = config.dac.modbus_comm_timeout_register;
    dac.watchdog.timeout = std::chrono::duration_cast<std::chrono::nanoseconds>(
        std::chrono::duration<double>(config.dac.modbus_comm_timeout_s));
    dac.watchdog.timeout_counts = static_cast<std::uint16_t>(std::clamp(
        std::lround(config.dac.modbus_comm_timeout_s * config.dac.modbus_comm_timeout_counts_per_s),
        1L, 65535L));
    dac.watchdog.safe_value_register = config.dac.modbus_safe_value_register;
    return std::make_shared<io::hw::ModbusAnalogOutput>(dac);
  }
  io::hw::IioAnalogOutputConfig dac;
  dac.channel.device = config.dac.iio_device;
  dac.channel.channel = config.dac.channel;
  dac.channel.scale_mv_override = config.dac.iio_scale_mv;
  dac.full_scale_volts = config.dac.full_scale_v;
  dac.safe_volts = safe_volts;
  return std::make_shared<io::hw::IioAnalogOutput>(dac);
}

}  // namespace

PressureConverters make_hw_pressure_converters(const Config& config, const io::Clock& clock) {
  PressureConverters c;
  c.sensor = pressure_sensor_config(config);
  c.drive = valve_drive_config(config);
  c.adc = make_adc(config, clock);
  c.dac = make_hw_return_valve(config);
  return c;
}

std::shared_ptr<io::AnalogOutput> make_hw_return_valve(const Config& config) {
  // Safe: return valve fully open, so the line holds no pressure.
  return make_dac(config, io::dac_volts_from_valve_opening(1.0, valve_drive_config(config)));
}

}  // namespace weedspray::daemon
