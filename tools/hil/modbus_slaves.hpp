// SPDX-License-Identifier: Apache-2.0
// The Modbus RTU modules of the simulated board, as libmodbus slaves on the master side of a
// pty pair: the daemon opens the pty's slave side (a symlink such as /run/weedspray-hil/analog)
// as its serial port, exactly as it opens an RS-485 adapter.
//   analog bus: slave adc_id answers function 04 with the pressure transmitter's voltage,
//               slave dac_id takes function 06 writes of the return valve's DAC voltage;
//   tank bus:   slave tank_id answers function 03 with the tank level.
// The register values live in ModbusBoard (shared with the plant loop under its mutex).
#pragma once

#include <cstdint>
#include <mutex>
#include <string>

namespace weedspray::hil {

struct ModbusBoard {
  std::mutex mutex;
  std::uint16_t adc_counts = 0;   // input register: volts / volts_per_count
  std::uint16_t dac_counts = 0;   // holding register written by the daemon
  std::uint64_t dac_writes = 0;   // how many function-06 writes arrived
  std::uint16_t tank_counts = 0;  // holding register: percent / percent_per_count
  std::uint64_t analog_requests = 0;
  std::uint64_t tank_requests = 0;
  std::uint64_t bad_frames = 0;
};

struct ModbusBusConfig {
  std::string link;  // symlink made to the pty's slave side
  int adc_id = 2;
  int dac_id = 3;
  int tank_id = 1;
  int register_address = 0;  // the same address on every module (the daemon's defaults)
};

// Each starts a thread serving its bus until the process exits; throws on set-up errors.
void start_analog_bus(const ModbusBusConfig& config, ModbusBoard& board);
void start_tank_bus(const ModbusBusConfig& config, ModbusBoard& board);

}  // namespace weedspray::hil
