// SPDX-License-Identifier: Apache-2.0
// A PulseInput on libgpiod 1.6 edge events: a SCHED_FIFO thread (ThreadRole::kPulseInput)
// reads events in bulk from the line's event fd (gpiod_line_event_read_fd_multiple into a fixed
// array: no allocation) and publishes {count, last edge kernel timestamp, errors} wait-free.
//
// Only the counted edge is requested, so every event is exactly one pulse (with both edges the
// uAPI v1 kernel derives the direction by re-reading the level, which is wrong at high rates).
// Loss detection is limited by uAPI v1 (the only one libgpiod 1.6 speaks): its event queue holds
// 16 events and drops silently when full, so a bulk read that returns >= 16 events is counted in
// overflow_count as "events may have been lost"; interrupts coalesced before the kernel's
// threaded handler runs are not detectable at all (uAPI v2 sequence numbers would be).
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <string>

#include "io/latest_value.hpp"
#include "io/linux/gpio_config.hpp"
#include "io/pulse_input.hpp"
#include "io/realtime.hpp"

namespace weedspray::io::hw {

enum class PulseEdge { kRising, kFalling };

struct GpioPulseInputConfig {
  std::string chip;  // as in GpioOutputBankConfig; may be empty with a line name
  GpioLineConfig line;
  PulseEdge counted_edge = PulseEdge::kRising;  // logical edge (after active_low) that counts
  GpioBias bias = GpioBias::kAsIs;
  std::string consumer = "weedsprayd";
};

class GpioPulseInput final : public PulseInput {
 public:
  // Requests the line for edge events and starts the reader thread. Throws std::runtime_error
  // naming the chip/line on failure.
  explicit GpioPulseInput(const GpioPulseInputConfig& config);
  ~GpioPulseInput() override;  // stops the thread, releases the line
  GpioPulseInput(const GpioPulseInput&) = delete;
  GpioPulseInput& operator=(const GpioPulseInput&) = delete;

  PulseSnapshot snapshot() const noexcept override;
  RtStatus thread_status() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace weedspray::io::hw
