// SPDX-License-Identifier: Apache-2.0
#include "io/linux/modbus_rtu.hpp"

#include <modbus/modbus.h>

#include <cerrno>
#include <stdexcept>

namespace weedspray::io::hw {

void ModbusDeleter::operator()(_modbus* ctx) const noexcept {
  modbus_close(ctx);
  modbus_free(ctx);
}

namespace detail {

ModbusContext open_modbus_rtu(const ModbusRtuSettings& c, const std::string& what,
                              ModbusRecovery recovery) {
  const std::string where = what + " (" + c.device + "): ";
  if (c.parity != 'N' && c.parity != 'E' && c.parity != 'O')
    throw std::runtime_error(where + "parity must be 'N', 'E' or 'O', got '" +
                             std::string(1, c.parity) + "'");
  if (c.baud <= 0) throw std::runtime_error(where + "baud must be > 0");
  if (c.data_bits < 5 || c.data_bits > 8)
    throw std::runtime_error(where + "data_bits must be 5..8");
  if (c.stop_bits != 1 && c.stop_bits != 2)
    throw std::runtime_error(where + "stop_bits must be 1 or 2");
  if (c.slave_id < 1 || c.slave_id > 247)
    throw std::runtime_error(where + "slave_id must be 1..247");
  if (c.response_timeout.count() <= 0)
    throw std::runtime_error(where + "response_timeout must be > 0");

  ModbusContext ctx(modbus_new_rtu(c.device.c_str(), c.baud, c.parity, c.data_bits, c.stop_bits));
  if (!ctx)
    throw std::runtime_error(where + "cannot create an RTU context: " + modbus_strerror(errno));
  modbus_set_slave(ctx.get(), c.slave_id);
  const auto us = std::chrono::duration_cast<std::chrono::microseconds>(c.response_timeout).count();
  modbus_set_response_timeout(ctx.get(), static_cast<std::uint32_t>(us / 1'000'000),
                              static_cast<std::uint32_t>(us % 1'000'000));
  const auto byte_us =
      std::chrono::duration_cast<std::chrono::microseconds>(c.byte_timeout).count();
  if (byte_us > 0)
    modbus_set_byte_timeout(ctx.get(), static_cast<std::uint32_t>(byte_us / 1'000'000),
                            static_cast<std::uint32_t>(byte_us % 1'000'000));
  // After a bad frame, wait out the line and flush, so garbage does not poison the next read.
  modbus_set_error_recovery(ctx.get(), recovery == ModbusRecovery::kWaitAndFlush
                                           ? MODBUS_ERROR_RECOVERY_PROTOCOL
                                           : MODBUS_ERROR_RECOVERY_NONE);
  if (modbus_connect(ctx.get()) != 0)
    throw std::runtime_error(where + "cannot open the serial port: " + modbus_strerror(errno));
  return ctx;
}

ModbusErrorKind classify_modbus_error(int err) noexcept {
  if (err == ETIMEDOUT) return ModbusErrorKind::kTimeout;
  if (err == EMBBADCRC) return ModbusErrorKind::kCrc;
  if (err == EMBBADDATA || err == EMBBADEXC || err == EMBUNKEXC || err == EMBMDATA ||
      err == EMBBADSLAVE || (err >= EMBXILFUN && err <= EMBXGTAR))
    return ModbusErrorKind::kInvalid;
  return ModbusErrorKind::kPort;
}

void recover_after_error(_modbus* ctx, int err, std::chrono::nanoseconds now,
                         std::chrono::nanoseconds& last_reopen) noexcept {
  if (classify_modbus_error(err) != ModbusErrorKind::kPort) {
    modbus_flush(ctx);
    return;
  }
  if (now - last_reopen < std::chrono::seconds(1)) return;
  last_reopen = now;
  modbus_close(ctx);
  modbus_connect(ctx);
}

}  // namespace detail
}  // namespace weedspray::io::hw
