// SPDX-License-Identifier: Apache-2.0
// The Modbus RTU module of the simulated machine, as a libmodbus slave on the master side of a
// pty pair: the daemon opens the pty's slave side (a symlink such as /run/weedspray-hil/tank) as
// its serial port, exactly as it opens an RS-485 adapter. Slave tank_id answers function 03
// with the tank level. The register value lives in ModbusBoard (shared with the plant loop
// under its mutex).
#pragma once

#include <cstdint>
#include <mutex>
#include <string>

namespace weedspray::hil {

struct ModbusBoard {
  std::mutex mutex;
  std::uint16_t tank_counts = 0;  // holding register: percent / percent_per_count
  std::uint64_t tank_requests = 0;
};

struct ModbusBusConfig {
  std::string link;  // symlink made to the pty's slave side
  int tank_id = 1;
  int register_address = 0;  // the daemon's default
};

// Starts a thread serving the bus until the process exits; throws on set-up errors.
void start_tank_bus(const ModbusBusConfig& config, ModbusBoard& board);

}  // namespace weedspray::hil
