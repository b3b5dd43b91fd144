// SPDX-License-Identifier: Apache-2.0
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
  // Longest silence inside a reply before it counts as cut off. libmodbus's default is 500 ms,
  // which holds a reader that long on every torn frame; 50 ms is over three times a USB-RS485
  // adapter's 16 ms latency timer (the longest gap a healthy reply shows).
  std::chrono::milliseconds byte_timeout{50};
};

namespace detail {

// How a context gets over a bad frame. kWaitAndFlush is libmodbus's protocol recovery: it
// sleeps a whole response timeout, then flushes (fine on a slow polling thread). kFlushOnly
// leaves recovery to the caller, who flushes at once (recover_after_error): the pressure
// converters' real-time thread cannot lose a response timeout - its sample is stale after
// three loop periods.
enum class ModbusRecovery { kWaitAndFlush, kFlushOnly };

// Validates, creates, configures (slave, timeout, error recovery) and connects.
// Throws std::runtime_error starting with `what` and naming the device/setting.
ModbusContext open_modbus_rtu(const ModbusRtuSettings& settings, const std::string& what,
                              ModbusRecovery recovery = ModbusRecovery::kWaitAndFlush);

// After a failed transaction on a kFlushOnly context: a bad frame or timeout discards what is
// left in the input buffer (tcflush, no sleep); a port error reopens the port, at most once a
// second (`last_reopen`, `now` on the caller's clock). Allocation-free.
void recover_after_error(_modbus* ctx, int err, std::chrono::nanoseconds now,
                         std::chrono::nanoseconds& last_reopen) noexcept;

// The libmodbus error classes the backends count.
enum class ModbusErrorKind { kTimeout, kCrc, kInvalid, kPort };
ModbusErrorKind classify_modbus_error(int err) noexcept;

}  // namespace detail
}  // namespace weedspray::io::hw
