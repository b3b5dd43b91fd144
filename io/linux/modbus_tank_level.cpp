// SPDX-License-Identifier: Apache-2.0
#include "io/linux/modbus_tank_level.hpp"

#include <modbus/modbus.h>

#include <cerrno>
#include <cmath>
#include <stdexcept>

namespace weedspray::io::hw {

ModbusTankLevel::ModbusTankLevel(const ModbusTankLevelConfig& config, const Clock& clock)
    : config_(config), clock_(clock) {
  if (config_.register_address < 0 || config_.register_address > 0xFFFF)
    throw std::runtime_error("modbus tank level (" + config_.device +
                             "): register_address must be 0..65535");
  ctx_ = detail::open_modbus_rtu(
      {config_.device, config_.baud, config_.parity, config_.data_bits, config_.stop_bits,
       config_.slave_id, config_.response_timeout, config_.byte_timeout},
      "modbus tank level");
}

ModbusTankLevel::~ModbusTankLevel() = default;

TankLevelSample ModbusTankLevel::read() noexcept {
  ++counters_.reads;
  std::uint16_t raw = 0;
  const int rc = config_.register_type == ModbusRegisterType::kHolding
                     ? modbus_read_registers(ctx_.get(), config_.register_address, 1, &raw)
                     : modbus_read_input_registers(ctx_.get(), config_.register_address, 1, &raw);
  const int err = errno;
  counters_.time = clock_.now();
  counters_.ok = false;
  if (rc == 1) {
    const double pct = raw * config_.percent_per_count + config_.offset_pct;
    if (std::isfinite(pct) && pct >= 0.0 && pct <= config_.max_valid_pct) {
      counters_.level_pct = pct;
      counters_.ok = true;
      last_error_.clear();
      return counters_;
    }
    ++counters_.invalid_responses;
    last_error_ =
        "level out of range: raw " + std::to_string(raw) + " -> " + std::to_string(pct) + " %";
    return counters_;
  }
  last_error_ = std::string("read of register ") + std::to_string(config_.register_address) +
                " from slave " + std::to_string(config_.slave_id) + " on " + config_.device +
                " failed: " + modbus_strerror(err);
  switch (detail::classify_modbus_error(err)) {
    case detail::ModbusErrorKind::kTimeout:
      ++counters_.timeouts;
      break;
    case detail::ModbusErrorKind::kCrc:
      ++counters_.crc_errors;
      break;
    case detail::ModbusErrorKind::kInvalid:
      ++counters_.invalid_responses;
      break;
    case detail::ModbusErrorKind::kPort:
      ++counters_.other_errors;
      // The port itself failed (unplugged adapter): reopen for the next read.
      modbus_close(ctx_.get());
      modbus_connect(ctx_.get());
      break;
  }
  return counters_;
}

std::string ModbusTankLevel::last_error() const {
  return last_error_;
}

}  // namespace weedspray::io::hw
