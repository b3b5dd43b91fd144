// SPDX-License-Identifier: Apache-2.0
// The configuration keys of [gpio], [adc], [dac], [analog_modbus], [flow]: the board's lines and
// converters.
#include <climits>

#include "daemon/config/config_key_tables.hpp"

// GCC 12 reports a false -Wmaybe-uninitialized inside std::variant<..., std::string> when the
// key table is built (GCC bug 107138 and relatives); the table is plain constant data.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace weedspray::daemon::key_tables {

void append_wiring_keys(std::vector<KeySpec<Config>>& keys) {
  // clang-format off
  keys.insert(keys.end(), {
    // [gpio]
    {WS_KEY(gpio, chip), std::string("gpiochip0"), 0, 0, "",
     "GPIO chip (name or /dev path) holding every line below"},
    {WS_KEY(gpio, valve_offsets), std::vector<int>{}, 0, 1023, "line",
     "valve line offsets, one per nozzle in boom order (empty = not wired)"},
    {WS_KEY(gpio, valve_names), std::vector<std::string>{}, 0, 0, "",
     "valve line names instead of offsets, one per nozzle (as in gpioinfo; empty = use offsets)"},
    {WS_KEY(gpio, valve_active_low), false, 0, 1, "",
     "valve lines are active-low"},
    {WS_KEY(gpio, pump_offset), -1, -1, 1023, "line",
     "pump relay line (-1 = not wired)"},
    {WS_KEY(gpio, pump_name), std::string(""), 0, 0, "",
     "pump relay line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, pump_active_low), false, 0, 1, "",
     "pump relay line is active-low"},
    {WS_KEY(gpio, buzzer_offset), -1, -1, 1023, "line",
     "alarm buzzer line (-1 = none)"},
    {WS_KEY(gpio, buzzer_name), std::string(""), 0, 0, "",
     "alarm buzzer line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, led_offset), -1, -1, 1023, "line", "alarm LED line (-1 = none)"},
    {WS_KEY(gpio, led_name), std::string(""), 0, 0, "",
     "alarm LED line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, heartbeat_offset), -1, -1, 1023, "line",
     "heartbeat output (-1 = none): a square wave from the valve thread while the real-time "
     "core runs, low when it stops, while a Fault is latched and after a refused valve or pump "
     "write; drives a retriggerable relay that powers the valves (and the pump)"},
    {WS_KEY(gpio, heartbeat_name), std::string(""), 0, 0, "",
     "heartbeat line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, heartbeat_hz), 50.0, 1, 250, "Hz",
     "heartbeat square-wave frequency (the relay's hold-up time must exceed a few periods)"},
    {WS_KEY(gpio, heartbeat_opt_out), false, 0, 1, "",
     "hardware mode starts only with a heartbeat output (heartbeat_offset or heartbeat_name), "
     "the channel that cuts valves and pump when the daemon stops driving them; true starts "
     "without one, with a warning at every start"},
    {WS_KEY(gpio, key_offset), -1, -1, 1023, "line",
     "start/stop key input (-1 = none); each press toggles Idle/Spraying"},
    {WS_KEY(gpio, key_name), std::string(""), 0, 0, "",
     "start/stop key line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, key_active_low), true, 0, 1, "",
     "start/stop key pulls the line low when pressed"},
    {WS_KEY(gpio, estop_offset), -1, -1, 1023, "line",
     "emergency-stop input (-1 = none): a normally closed circuit; when it opens (a pressed "
     "button, a cut wire) valves close and the pump stops within milliseconds, latched until "
     "the circuit is closed again and the alarms are cleared"},
    {WS_KEY(gpio, estop_name), std::string(""), 0, 0, "",
     "emergency-stop line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, estop_active_low), true, 0, 1, "",
     "the closed E-stop circuit pulls the line low (contact to ground, pull-up resistor): an "
     "open circuit reads high"},
    {WS_KEY(gpio, estop_opt_out), false, 0, 1, "",
     "hardware mode starts only with an emergency-stop input (estop_offset or estop_name); "
     "true starts without one, with a warning at every start"},
    {WS_KEY(gpio, flow_offset), -1, -1, 1023, "line",
     "flow meter pulse input (-1 = none)"},
    {WS_KEY(gpio, flow_name), std::string(""), 0, 0, "",
     "flow meter line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, wheel_offset), -1, -1, 1023, "line",
     "Hall wheel sensor pulse input (-1 = none)"},
    {WS_KEY(gpio, wheel_name), std::string(""), 0, 0, "",
     "Hall wheel sensor line by name instead of offset (empty = use the offset)"},
    // [adc]
    {WS_KEY(adc, source), std::string("iio"), 0, 0, "",
     "the pressure ADC: a Linux IIO device, or a Modbus RTU analog input module on the "
     "[analog_modbus] bus", {"iio", "modbus"}},
    {WS_KEY(adc, iio_device), std::string("iio:device0"), 0, 0, "",
     "IIO device reading the pressure sensor: iio:deviceN, its path, or its name (ads1015)"},
    {WS_KEY(adc, pressure_channel), 0, 0, 63, "",
     "IIO input channel N (in_voltageN_raw) of the pressure sensor"},
    {WS_KEY(adc, iio_scale_mv), 0.0, 0, 1e6, "mV/count",
     "IIO millivolts per count, for a driver without in_voltageN_scale or in_voltage_scale "
     "(0 = read the driver's scale)"},
    {WS_KEY(adc, shunt_ohms), 165.0, 1, 10000, "ohm",
     "I/V resistor of the 4-20 mA loop (165 ohm maps 20 mA to 3.3 V)"},
    {WS_KEY(adc, modbus_slave_id), 2, 1, 247, "",
     "source = \"modbus\": the input module's slave address"},
    {WS_KEY(adc, modbus_register), 0, 0, 65535, "",
     "source = \"modbus\": the register holding the sensor voltage"},
    {WS_KEY(adc, modbus_register_type), std::string("input"), 0, 0, "",
     "source = \"modbus\": read it as an input register (function 04) or a holding register "
     "(03)", {"input", "holding"}},
    {WS_KEY(adc, modbus_volts_per_count), 0.001, 1e-9, 1, "V/count",
     "source = \"modbus\": volts = register value x this (the module's unit, e.g. mV)"},
    // [dac]
    {WS_KEY(dac, source), std::string("iio"), 0, 0, "",
     "the return-valve DAC: a Linux IIO device, or a Modbus RTU analog output module on the "
     "[analog_modbus] bus", {"iio", "modbus"}},
    {WS_KEY(dac, iio_device), std::string("iio:device1"), 0, 0, "",
     "IIO device driving the proportional return valve"},
    {WS_KEY(dac, channel), 0, 0, 63, "", "IIO output channel N (out_voltageN_raw)"},
    {WS_KEY(dac, iio_scale_mv), 0.0, 0, 1e6, "mV/count",
     "IIO millivolts per count, for a driver without out_voltageN_scale or out_voltage_scale "
     "(0 = read the driver's scale)"},
    {WS_KEY(dac, full_scale_v), 3.3, 0.5, 12, "V",
     "DAC voltage for a 100 % valve command"},
    {WS_KEY(dac, return_valve_open_at), std::string("full_scale"), 0, 0, "",
     "the DAC output that opens the return valve fully, its safe position (no pressure held): "
     "full_scale for a valve that opens with its control voltage (then a DAC reset, a "
     "brown-out or a broken wire closes it: wire a fail-open bypass, docs/hardware.md), zero "
     "for a reverse-acting valve that opens at 0 V, so a dead DAC opens the relief path",
     {"full_scale", "zero"}},
    {WS_KEY(dac, modbus_slave_id), 3, 1, 247, "",
     "source = \"modbus\": the output module's slave address"},
    {WS_KEY(dac, modbus_register), 0, 0, 65535, "",
     "source = \"modbus\": the holding register written with the valve voltage (function 06)"},
    {WS_KEY(dac, modbus_volts_per_count), 0.001, 1e-9, 1, "V/count",
     "source = \"modbus\": register value = volts / this"},
    {WS_KEY(dac, modbus_comm_timeout_register), -1, -1, 65535, "",
     "source = \"modbus\": the module's communication-timeout holding register (its manual: "
     "\"watchdog\", \"communication loss\" or \"host timeout\"), so that the module itself "
     "sets its output safe when the daemon stops writing (a crash, a freeze, a cut RS-485 "
     "pair); the daemon then rewrites an unchanged value every third of the timeout. -1: "
     "the module has none"},
    {WS_KEY(dac, modbus_comm_timeout_s), 0.5, 0.05, 60, "s",
     "source = \"modbus\": the communication timeout written there"},
    {WS_KEY(dac, modbus_comm_timeout_counts_per_s), 1000.0, 0.001, 1e6, "counts/s",
     "source = \"modbus\": the timeout register's unit, as counts per second (1000: "
     "milliseconds, 10: tenths of a second, 1: seconds)"},
    {WS_KEY(dac, modbus_safe_value_register), -1, -1, 65535, "",
     "source = \"modbus\": the holding register of the value the module puts out on a "
     "communication loss (and, on many modules, at power-up); written with the return valve's "
     "safe value at start. -1: the module has none"},
    {WS_KEY(dac, write_failures_tolerated), 2, 0, 20, "",
     "failed DAC writes in a row that are only counted and logged, not a fault: each is "
     "superseded by the next pressure-loop period's write and the valve holds its last value "
     "meanwhile (2, like a pressure sample that goes stale after 3 periods); the next failure "
     "raises output_write_failed, and a failed safe write always does"},
    // [analog_modbus]
    {WS_KEY(analog_modbus, device), std::string("/dev/ttyUSB1"), 0, 0, "path",
     "RS-485 serial device of the Modbus analog modules; not the tank sensor's [modbus] port, "
     "which another thread polls"},
    {WS_KEY(analog_modbus, baud), 115200, 1200, 921600, "baud",
     "serial speed: a one-register transaction is about 22 character times, 2.1 ms at 115200 "
     "and 25 ms at 9600; it must fit in half a pressure-loop period"},
    {WS_KEY(analog_modbus, parity), std::string("N"), 0, 0, "", "serial parity",
     {"N", "E", "O"}},
    {WS_KEY(analog_modbus, timeout_s), 0.02, 0.005, 1, "s",
     "response timeout; a module silent for 3 pressure-loop periods makes the sensor stale "
     "(pump off, valves closed)"},
    // [flow]
    {WS_KEY(flow, pulses_per_litre), 8500.0, 1, 1e6, "pulses/L",
     "flow meter constant"},
    {WS_KEY(flow, counter), std::string(""), 0, 0, "",
     "count the flow meter in the kernel (Linux Counter subsystem, e.g. interrupt-cnt bound to "
     "the meter's GPIO in the device tree) instead of GPIO edge events: counterN, its path, or "
     "its name. For meters pulsing faster than ~10 kHz, where edge events can be lost. Empty = "
     "gpio.flow_offset / gpio.flow_name"},
  });
  // clang-format on
}

}  // namespace weedspray::daemon::key_tables
