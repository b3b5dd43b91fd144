// SPDX-License-Identifier: Apache-2.0
// Pulse counters: the flow meter and the Hall wheel sensor. The backend counts edges on its own
// thread; the real-time side reads a consistent snapshot without waiting.
#pragma once

#include <chrono>
#include <cstdint>

namespace weedspray::io {

struct PulseSnapshot {
  std::uint64_t count = 0;                    // edges counted since start
  std::chrono::nanoseconds last_edge_time{};  // kernel timestamp of the latest counted edge
  std::uint64_t error_count = 0;              // read errors of the backend
  std::uint64_t overflow_count = 0;           // events the kernel dropped (queue overflow)
};

class PulseInput {
 public:
  virtual ~PulseInput() = default;
  // Wait-free; safe from any thread.
  virtual PulseSnapshot snapshot() const noexcept = 0;
};

}  // namespace weedspray::io
