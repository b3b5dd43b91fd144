#include "io/linux/modbus_tank_level.hpp"

#include <modbus/modbus.h>

#include <cerrno>
#include <cmath>
#include <stdexcept>

namespace weedspray::io::hw {

void ModbusDeleter::operator()(_modbus* ctx) const noexcept {
  modbus_close(ctx);
  modbus_free(ctx);
}

namespace {

void check_config(const ModbusTankLevelConfig& c) {
  const std::string where = "modbus tank level (" + c.device + "): ";
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
  if (c.register_address < 0 || c.register_address > 0xFFFF)
    throw std::runtime_error(where + "register_address must be 0..65535");
  if (c.response_timeout.count() <= 0)
    throw std::runtime_error(where + "response_timeout must be > 0");
}

}  // namespace

ModbusTankLevel::ModbusTankLevel(const ModbusTankLevelConfig& config, const Clock& clock)
    : config_(config), clock_(clock) {
  check_config(config_);
  ctx_.reset(modbus_new_rtu(config_.device.c_str(), config_.baud, config_.parity, config_.data_bits,
                            config_.stop_bits));
  if (!ctx_)
    throw std::runtime_error("modbus tank level: cannot create an RTU context for " +
                             config_.device + ": " + modbus_strerror(errno));
  modbus_set_slave(ctx_.get(), config_.slave_id);
  const auto timeout_us =
      std::chrono::duration_cast<std::chrono::microseconds>(config_.response_timeout);
  modbus_set_response_timeout(ctx_.get(),
                              static_cast<std::uint32_t>(timeout_us.count() / 1'000'000),
                              static_cast<std::uint32_t>(timeout_us.count() % 1'000'000));
  // After a bad frame, wait out the line and flush, so garbage does not poison the next read.
  modbus_set_error_recovery(ctx_.get(), MODBUS_ERROR_RECOVERY_PROTOCOL);
  if (modbus_connect(ctx_.get()) != 0)
    throw std::runtime_error("modbus tank level: cannot open serial port " + config_.device + ": " +
                             modbus_strerror(errno));
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
  if (err == ETIMEDOUT) {
    ++counters_.timeouts;
  } else if (err == EMBBADCRC) {
    ++counters_.crc_errors;
  } else if (err == EMBBADDATA || err == EMBBADEXC || err == EMBUNKEXC || err == EMBMDATA ||
             err == EMBBADSLAVE || (err >= EMBXILFUN && err <= EMBXGTAR)) {
    ++counters_.invalid_responses;
  } else {
    ++counters_.other_errors;
    // The port itself failed (unplugged adapter): reopen for the next read.
    modbus_close(ctx_.get());
    modbus_connect(ctx_.get());
  }
  return counters_;
}

std::string ModbusTankLevel::last_error() const {
  return last_error_;
}

}  // namespace weedspray::io::hw
