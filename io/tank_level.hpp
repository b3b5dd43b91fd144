// SPDX-License-Identifier: Apache-2.0
// Tank level (ultrasonic sensor on RS-485 Modbus RTU). Reads block for up to the response
// timeout: only ever on a worker thread, which publishes the result into a LatestValue.
#pragma once

#include <chrono>
#include <cstdint>

namespace weedspray::io {

struct TankLevelSample {
  double level_pct = 0.0;               // meaningful only when ok
  std::chrono::nanoseconds time{};      // when the read completed
  std::uint64_t reads = 0;              // read attempts since start
  std::uint64_t timeouts = 0;           // no (complete) answer within the response timeout
  std::uint64_t crc_errors = 0;         // CRC mismatch
  std::uint64_t invalid_responses = 0;  // wrong slave/function/length, exception, out of range
  std::uint64_t other_errors = 0;       // serial port errors
  bool ok = false;                      // this read produced a level
};

class TankLevelSensor {
 public:
  virtual ~TankLevelSensor() = default;
  // One blocking read; never throws. Counters are cumulative.
  virtual TankLevelSample read() noexcept = 0;
};

}  // namespace weedspray::io
