// A PulseInput on libgpiod 1.6 edge events: a SCHED_FIFO thread (ThreadRole::kPulseInput)
// reads events in bulk from the line's event fd (gpiod_line_event_read_fd_multiple into a fixed
// array: no allocation) and publishes {count, last edge kernel timestamp, errors} wait-free.
//
// Both edges are requested so lost events are detectable: the uAPI v1 kernel queue (16 events)
// drops silently when full, and two consecutive edges of the same direction prove a loss;
// those are counted in overflow_count.
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
