// SPDX-License-Identifier: Apache-2.0
#include "io/linux/modbus_analog.hpp"

#include <time.h>

#include <modbus/modbus.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <stdexcept>

namespace weedspray::io::hw {

namespace {

// The output has no injected clock; the monotonic clock only rate-limits port reopening.
std::chrono::nanoseconds reopen_clock() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::chrono::seconds{ts.tv_sec} + std::chrono::nanoseconds{ts.tv_nsec};
}

void check_register(int address, const std::string& what, const std::string& device) {
  if (address < 0 || address > 0xFFFF)
    throw std::runtime_error(what + " (" + device + "): register_address must be 0..65535");
}

}  // namespace

ModbusAnalogInput::ModbusAnalogInput(const ModbusAnalogInputConfig& config, const Clock& clock)
    : config_(config), clock_(clock) {
  check_register(config.register_address, "modbus analog input", config.port.device);
  if (!(config.volts_per_count > 0.0))
    throw std::runtime_error("modbus analog input (" + config.port.device +
                             "): volts_per_count must be > 0");
  ctx_ = detail::open_modbus_rtu(config.port, "modbus analog input",
                                 detail::ModbusRecovery::kFlushOnly);
}

AnalogSample ModbusAnalogInput::read() noexcept {
  AnalogSample s;
  std::uint16_t raw = 0;
  const int rc = config_.input_register
                     ? modbus_read_input_registers(ctx_.get(), config_.register_address, 1, &raw)
                     : modbus_read_registers(ctx_.get(), config_.register_address, 1, &raw);
  const int err = errno;
  s.time = clock_.now();
  if (rc == 1) {
    s.volts = raw * config_.volts_per_count;
    s.ok = true;
  } else {
    ++errors_;
    last_errno_ = err;
    detail::recover_after_error(ctx_.get(), err, s.time, last_reopen_);
  }
  s.error_count = errors_;
  return s;
}

std::string ModbusAnalogInput::last_error() const {
  return last_errno_ == 0 ? std::string() : modbus_strerror(last_errno_);
}

ModbusAnalogOutput::ModbusAnalogOutput(const ModbusAnalogOutputConfig& config) : config_(config) {
  check_register(config.register_address, "modbus analog output", config.port.device);
  if (!(config.volts_per_count > 0.0))
    throw std::runtime_error("modbus analog output (" + config.port.device +
                             "): volts_per_count must be > 0");
  const ModbusCommWatchdog& watchdog = config.watchdog;
  if (watchdog.timeout_register >= 0) {
    check_register(watchdog.timeout_register, "modbus analog output watchdog", config.port.device);
    if (watchdog.timeout_counts == 0 || watchdog.timeout <= std::chrono::nanoseconds::zero())
      throw std::runtime_error("modbus analog output (" + config.port.device +
                               "): the communication timeout must be > 0");
  }
  if (watchdog.safe_value_register >= 0)
    check_register(watchdog.safe_value_register, "modbus analog output safe value",
                   config.port.device);
  ctx_ = detail::open_modbus_rtu(config.port, "modbus analog output",
                                 detail::ModbusRecovery::kFlushOnly);
  // The safe value first: a timeout armed before it would put out whatever the module held.
  const auto store = [&](int address, std::uint16_t value, const char* what) {
    if (address < 0) return;
    if (modbus_write_register(ctx_.get(), address, value) != 1)
      throw std::runtime_error("modbus analog output (" + describe() + "): writing " + what +
                               " to holding register " + std::to_string(address) +
                               " failed: " + modbus_strerror(errno) +
                               " (a module without that register: set it to -1)");
  };
  store(watchdog.safe_value_register, counts(config.safe_volts), "the safe value");
  store(watchdog.timeout_register, watchdog.timeout_counts, "the communication timeout");
  if (write(config.safe_volts) != 0)
    throw std::runtime_error("modbus analog output (" + config.port.device +
                             "): writing the safe value failed: " + modbus_strerror(errno));
}

ModbusAnalogOutput::~ModbusAnalogOutput() {
  force_safe();
}

std::uint16_t ModbusAnalogOutput::counts(double volts) const noexcept {
  const double clamped =
      std::clamp(std::isfinite(volts) ? volts : config_.safe_volts, 0.0, config_.full_scale_volts);
  return static_cast<std::uint16_t>(
      std::clamp(std::lround(clamped / config_.volts_per_count), 0L, 0xFFFFL));
}

std::chrono::nanoseconds ModbusAnalogOutput::rewrite_within() const noexcept {
  return config_.watchdog.timeout_register >= 0 ? config_.watchdog.timeout / 3
                                                : std::chrono::nanoseconds::zero();
}

int ModbusAnalogOutput::write(double volts) noexcept {
  if (modbus_write_register(ctx_.get(), config_.register_address, counts(volts)) != 1) {
    const int err = errno;
    ++errors_;
    detail::recover_after_error(ctx_.get(), err, reopen_clock(), last_reopen_);
    return err > 0 ? -err : -EIO;
  }
  return 0;
}

std::string ModbusAnalogOutput::describe() const {
  return "Modbus " + config_.port.device + " slave " + std::to_string(config_.port.slave_id) +
         " holding register " + std::to_string(config_.register_address);
}

int ModbusAnalogOutput::force_safe() noexcept {
  // Two tries: each failed one already flushed the line (and at most once a second reopened it).
  return write_with_retries(*this, config_.safe_volts, 2);
}

}  // namespace weedspray::io::hw
