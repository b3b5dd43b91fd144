// SPDX-License-Identifier: Apache-2.0
// The tank level sensor over Modbus RTU (libmodbus 3.1). Blocking reads with a response
// timeout: only on a worker thread (ThreadRole::kModbus), never on an RT thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "io/clock.hpp"
#include "io/linux/modbus_rtu.hpp"
#include "io/tank_level.hpp"

namespace weedspray::io::hw {

enum class ModbusRegisterType { kHolding, kInput };

struct ModbusTankLevelConfig {
  std::string device = "/dev/ttyUSB0";
  int baud = 9600;
  char parity = 'N';  // 'N', 'E' or 'O'
  int data_bits = 8;
  int stop_bits = 1;
  int slave_id = 1;
  int register_address = 0;  // protocol address (0-based)
  ModbusRegisterType register_type = ModbusRegisterType::kHolding;
  double percent_per_count = 0.1;  // level_pct = raw * percent_per_count + offset_pct
  double offset_pct = 0.0;
  double max_valid_pct = 100.0;  // above this (after scaling) the answer is invalid
  std::chrono::milliseconds response_timeout{500};
  std::chrono::milliseconds byte_timeout{50};  // see ModbusRtuSettings::byte_timeout
};

class ModbusTankLevel final : public TankLevelSensor {
 public:
  // Creates the context and opens the serial port. Throws std::runtime_error naming the device
  // and setting (bad parity, port cannot be opened ...).
  ModbusTankLevel(const ModbusTankLevelConfig& config, const Clock& clock);
  ~ModbusTankLevel() override;

  TankLevelSample read() noexcept override;
  // Human-readable reason of the last failed read ("" after a success).
  std::string last_error() const;

 private:
  ModbusTankLevelConfig config_;
  const Clock& clock_;
  ModbusContext ctx_;
  TankLevelSample counters_;
  std::string last_error_;
};

}  // namespace weedspray::io::hw
