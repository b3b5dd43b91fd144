// SPDX-License-Identifier: Apache-2.0
// Analog I/O through Modbus RTU analog modules (the alternative to IIO ADC/DAC chips): one
// register per channel, volts = raw * volts_per_count. Each read/write is one blocking Modbus
// transaction bounded by the response timeout (about 10 ms at 9600 baud, 1-2 ms at 115200):
// use a fast baud rate and give the module its own serial port — the pressure loop is its only
// user, so no lock is shared with the tank level worker.
#pragma once

#include <cstdint>
#include <string>

#include "io/analog.hpp"
#include "io/clock.hpp"
#include "io/linux/modbus_rtu.hpp"

namespace weedspray::io::hw {

struct ModbusAnalogInputConfig {
  ModbusRtuSettings port;
  int register_address = 0;
  bool input_register = true;  // function 04 (input registers), else 03 (holding)
  double volts_per_count = 0.001;
};

// A module's own fail-safe for a silent master (a crashed or frozen daemon, a cut RS-485 pair):
// when no write arrives within its communication timeout, the module sets its output to a
// stored safe value by itself. Both are holding registers whose addresses and units the
// module's manual gives; -1: the module has no such register.
struct ModbusCommWatchdog {
  int timeout_register = -1;
  std::uint16_t timeout_counts = 0;  // the timeout in the module's unit (e.g. ms, 0.1 s)
  std::chrono::nanoseconds timeout{0};
  int safe_value_register = -1;  // written with the safe value's counts
};

struct ModbusAnalogOutputConfig {
  ModbusRtuSettings port;
  int register_address = 0;  // holding register, written with function 06
  double volts_per_count = 0.001;
  double full_scale_volts = 10.0;
  double safe_volts = 0.0;
  ModbusCommWatchdog watchdog;
};

class ModbusAnalogInput final : public AnalogInput {
 public:
  // Throws std::runtime_error naming the device/setting.
  ModbusAnalogInput(const ModbusAnalogInputConfig& config, const Clock& clock);
  AnalogSample read() noexcept override;
  // The last failure in words (formatted here, not on the converters' thread).
  std::string last_error() const;

 private:
  ModbusAnalogInputConfig config_;
  const Clock& clock_;
  ModbusContext ctx_;
  std::uint64_t errors_ = 0;
  int last_errno_ = 0;
  std::chrono::nanoseconds last_reopen_{std::chrono::nanoseconds::min() / 2};
};

class ModbusAnalogOutput final : public AnalogOutput {
 public:
  // Opens the port, stores the safe value and the timeout in the module's watchdog registers
  // (those configured), then writes safe_volts. Throws std::runtime_error naming the device and
  // the register that failed.
  explicit ModbusAnalogOutput(const ModbusAnalogOutputConfig& config);
  ~ModbusAnalogOutput() override;  // force_safe()
  int write(double volts) noexcept override;
  int force_safe() noexcept override;
  std::string describe() const override;
  double full_scale_volts() const noexcept override { return config_.full_scale_volts; }
  std::uint64_t error_count() const noexcept override { return errors_; }
  // A third of the module's communication timeout, so that two lost writes in a row still
  // leave the output where it was; zero without a watchdog.
  std::chrono::nanoseconds rewrite_within() const noexcept override;

 private:
  std::uint16_t counts(double volts) const noexcept;

  ModbusAnalogOutputConfig config_;
  ModbusContext ctx_;
  std::uint64_t errors_ = 0;
  std::chrono::nanoseconds last_reopen_{std::chrono::nanoseconds::min() / 2};
};

}  // namespace weedspray::io::hw
