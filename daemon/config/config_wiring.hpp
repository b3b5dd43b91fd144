// SPDX-License-Identifier: Apache-2.0
// The configuration's sections [gpio] [adc] [dac] [analog_modbus] [flow]: the board's lines and
// converters. Part of Config (config.hpp); defaults, ranges and documentation are in the key table
// (config_keys_wiring.cpp).
#pragma once

#include <string>
#include <vector>

namespace weedspray::daemon {

struct GpioSection {
  std::string chip;
  // Each line is named by offset on `chip` or, when its *_name is not empty, by line name.
  std::vector<int> valve_offsets;  // one per nozzle, boom order; empty = not wired
  std::vector<std::string> valve_names;
  bool valve_active_low;
  int pump_offset;  // -1 = not wired
  std::string pump_name;
  bool pump_active_low;
  int buzzer_offset;
  std::string buzzer_name;
  int led_offset;
  std::string led_name;
  int heartbeat_offset;  // square wave while the valve thread runs (external dead-man relay)
  std::string heartbeat_name;
  double heartbeat_hz;
  bool heartbeat_opt_out;  // hardware mode without a heartbeat output: allowed, warned at start
  int key_offset;
  std::string key_name;
  bool key_active_low;
  int estop_offset;  // normally closed E-stop circuit; -1 = none
  std::string estop_name;
  bool estop_active_low;  // the closed circuit pulls the line low
  bool estop_opt_out;     // hardware mode without an E-stop input: allowed, warned at start
  int flow_offset;
  std::string flow_name;
  int wheel_offset;
  std::string wheel_name;
};

struct AdcSection {
  std::string source;  // iio|modbus
  std::string iio_device;
  int pressure_channel;
  double iio_scale_mv;  // mV per count; 0 = read in_voltageN_scale
  double shunt_ohms;    // I/V resistor of the 4-20 mA loop
  int modbus_slave_id;
  int modbus_register;
  std::string modbus_register_type;  // input|holding
  double modbus_volts_per_count;
};

struct DacSection {
  std::string source;  // iio|modbus
  std::string iio_device;
  int channel;
  double iio_scale_mv;  // mV per count; 0 = read out_voltageN_scale
  double full_scale_v;
  std::string return_valve_open_at;  // full_scale|zero: the DAC output that opens it fully
  int modbus_slave_id;
  int modbus_register;
  double modbus_volts_per_count;
  // The module's own fail-safe on a silent master (ModbusCommWatchdog); -1: none.
  int modbus_comm_timeout_register;
  double modbus_comm_timeout_s;
  double modbus_comm_timeout_counts_per_s;  // the module's unit of that register
  int modbus_safe_value_register;
  int write_failures_tolerated;  // in a row, before output_write_failed
};

// The RS-485 bus of the Modbus analog modules (adc/dac source = "modbus").
struct AnalogModbusSection {
  std::string device;
  int baud;
  std::string parity;  // N|E|O
  double timeout_s;
};

struct FlowSection {
  double pulses_per_litre;
  std::string counter;  // "" = GPIO edge events on gpio.flow_*; else a kernel counter device
};

}  // namespace weedspray::daemon
