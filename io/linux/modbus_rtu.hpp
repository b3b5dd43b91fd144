// Internal helper shared by the libmodbus backends: one RTU master context from serial
// settings, validated, with errors that name the device and setting.
#pragma once

#include <chrono>
#include <memory>
#include <string>

struct _modbus;

namespace weedspray::io::hw {

struct ModbusDeleter {
  void operator()(_modbus* ctx) const noexcept;
};
using ModbusContext = std::unique_ptr<_modbus, ModbusDeleter>;

struct ModbusRtuSettings {
  std::string device;
  int baud = 9600;
  char parity = 'N';
  int data_bits = 8;
  int stop_bits = 1;
  int slave_id = 1;
  std::chrono::milliseconds response_timeout{500};
};

namespace detail {

// Validates, creates, configures (slave, timeout, protocol error recovery) and connects.
// Throws std::runtime_error starting with `what` and naming the device/setting.
ModbusContext open_modbus_rtu(const ModbusRtuSettings& settings, const std::string& what);

// The libmodbus error classes the backends count.
enum class ModbusErrorKind { kTimeout, kCrc, kInvalid, kPort };
ModbusErrorKind classify_modbus_error(int err) noexcept;

}  // namespace detail
}  // namespace weedspray::io::hw
