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
  ctx_ = detail::open_modbus_rtu(config.port, "modbus analog output",
                                 detail::ModbusRecovery::kFlushOnly);
  if (write(config.safe_volts) != 0)
    throw std::runtime_error("modbus analog output (" + config.port.device +
                             "): writing the safe value failed: " + modbus_strerror(errno));
}

ModbusAnalogOutput::~ModbusAnalogOutput() {
  force_safe();
}

int ModbusAnalogOutput::write(double volts) noexcept {
  const double clamped =
      std::clamp(std::isfinite(volts) ? volts : config_.safe_volts, 0.0, config_.full_scale_volts);
  const long raw = std::clamp(std::lround(clamped / config_.volts_per_count), 0L, 0xFFFFL);
  if (modbus_write_register(ctx_.get(), config_.register_address,
                            static_cast<std::uint16_t>(raw)) != 1) {
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
