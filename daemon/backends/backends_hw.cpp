// SPDX-License-Identifier: Apache-2.0
// The board: libgpiod lines, the pressure converters (backends_hw_converters.cpp), V4L2 cameras,
// libmodbus tank sensor, configured from the [gpio], [modbus] and [[camera]] sections.
#include <cstring>
#include <stdexcept>

#include "daemon/backends/backends.hpp"
#include "daemon/backends/hw_output_lines.hpp"
#include "io/linux/counter_pulse_input.hpp"
#include "io/linux/gpio_digital_input.hpp"
#include "io/linux/gpio_estop_input.hpp"
#include "io/linux/gpio_output_bank.hpp"
#include "io/linux/gpio_pulse_input.hpp"
#include "io/linux/modbus_tank_level.hpp"
#include "io/linux/monotonic_clock.hpp"
#include "io/linux/v4l2_camera.hpp"

namespace weedspray::daemon {
namespace {

io::hw::CameraPixelFormat pixel_format(const std::string& name) {
  if (name == "MJPG") return io::hw::CameraPixelFormat::kMjpeg;
  if (name == "RGB3") return io::hw::CameraPixelFormat::kRgb24;
  if (name == "GREY") return io::hw::CameraPixelFormat::kGrey;
  return io::hw::CameraPixelFormat::kYuyv;
}

io::PulseInput* pulse_line(Backends& b, const GpioSection& gpio, const std::string& name,
                           int offset) {
  if (!wired(name, offset)) return nullptr;
  io::hw::GpioPulseInputConfig config;
  config.chip = gpio.chip;
  config.line.name = name;
  config.line.offset = offset;
  return keep(b, std::make_shared<io::hw::GpioPulseInput>(config));
}

// An input line's configuration (the key, the E-stop) on gpio.chip, by name or offset.
template <typename InputConfig>
InputConfig input_line(const GpioSection& gpio, const std::string& name, int offset,
                       bool active_low) {
  InputConfig input;
  input.chip = gpio.chip;
  input.line.name = name;
  input.line.offset = offset;
  input.line.active_low = active_low;
  return input;
}

}  // namespace

Backends make_hw_backends(const Config& config) {
  Backends b;
  b.mode = "hw";
  b.clock = keep(b, std::make_shared<io::hw::MonotonicClock>());
  const auto& gpio = config.gpio;
  if (gpio.valve_offsets.empty() && gpio.valve_names.empty()) {
    throw std::runtime_error(
        "gpio.valve_offsets and gpio.valve_names are empty: no valve lines to drive (use --sim "
        "to run without hardware)");
  }
  io::hw::GpioOutputBankConfig valves;
  valves.chip = gpio.chip;
  for (int offset : gpio.valve_offsets) {
    valves.lines.push_back(io::hw::GpioLineConfig{
        .name = {}, .offset = offset, .active_low = gpio.valve_active_low, .safe_value = false});
  }
  for (const auto& name : gpio.valve_names) {
    valves.lines.push_back(io::hw::GpioLineConfig{
        .name = name, .offset = -1, .active_low = gpio.valve_active_low, .safe_value = false});
  }
  // Lines are requested with their safe values as defaults: no valve glitches open here.
  b.valves = keep(b, std::make_shared<io::hw::GpioOutputBank>(valves));
  b.pump = single_line(b, gpio, gpio.pump_name, gpio.pump_offset, gpio.pump_active_low);
  b.buzzer = single_line(b, gpio, gpio.buzzer_name, gpio.buzzer_offset, false);
  b.led = single_line(b, gpio, gpio.led_name, gpio.led_offset, false);
  b.heartbeat = single_line(b, gpio, gpio.heartbeat_name, gpio.heartbeat_offset, false);
  if (config.flow.counter.empty()) {
    b.flow = pulse_line(b, gpio, gpio.flow_name, gpio.flow_offset);
  } else {
    io::hw::CounterPulseInputConfig counter;
    counter.device = config.flow.counter;
    b.flow = keep(b, std::make_shared<io::hw::CounterPulseInput>(counter));
  }
  b.wheel = config.wheel.source == "fixed"
                ? nullptr
                : pulse_line(b, gpio, gpio.wheel_name, gpio.wheel_offset);
  if (config.wheel.source == "pulses" && b.wheel == nullptr) {
    throw std::runtime_error(
        "wheel.source = \"pulses\" needs gpio.wheel_offset or gpio.wheel_name");
  }
  if (wired(gpio.key_name, gpio.key_offset)) {
    b.key = keep(
        b, std::make_shared<io::hw::GpioDigitalInput>(input_line<io::hw::GpioDigitalInputConfig>(
               gpio, gpio.key_name, gpio.key_offset, gpio.key_active_low)));
  }
  if (wired(gpio.estop_name, gpio.estop_offset)) {
    b.estop =
        keep(b, std::make_shared<io::hw::GpioEstopInput>(input_line<io::hw::GpioEstopInputConfig>(
                    gpio, gpio.estop_name, gpio.estop_offset, gpio.estop_active_low)));
  }

  PressureConverters converters = make_hw_pressure_converters(config, *b.clock);
  b.pressure_adc = keep(b, converters.adc);
  b.return_valve = keep(b, converters.dac);
  b.sensor = converters.sensor;
  b.drive = converters.drive;

  if (config.modbus.enabled) {
    io::hw::ModbusTankLevelConfig modbus;
    modbus.device = config.modbus.device;
    modbus.baud = config.modbus.baud;
    modbus.parity = config.modbus.parity.front();
    modbus.slave_id = config.modbus.slave_id;
    modbus.register_address = config.modbus.tank_register;
    modbus.percent_per_count = config.modbus.tank_scale_pct_per_count;
    modbus.response_timeout =
        std::chrono::milliseconds(static_cast<int>(config.modbus.timeout_s * 1000));
    b.tank = keep(b, std::make_shared<io::hw::ModbusTankLevel>(modbus, *b.clock));
  }
  for (const auto& camera : config.cameras) {
    io::hw::V4l2CameraConfig v4l2;
    v4l2.device = camera.device;
    v4l2.width = camera.width;
    v4l2.height = camera.height;
    v4l2.fps = static_cast<int>(camera.fps);
    v4l2.pixel_format = pixel_format(camera.format);
    if (camera.exposure_us > 0) v4l2.exposure_absolute = (camera.exposure_us + 50) / 100;
    if (camera.white_balance_k > 0) {
      v4l2.auto_white_balance = false;
      v4l2.white_balance_temperature = camera.white_balance_k;
    }
    b.cameras.push_back(keep(b, std::make_shared<io::hw::V4l2Camera>(v4l2, *b.clock)));
  }
  add_gnss(b, config);
  add_yaw_sensor(b, config);
  return b;
}

}  // namespace weedspray::daemon
