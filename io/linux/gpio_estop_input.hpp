// SPDX-License-Identifier: Apache-2.0
// The emergency-stop circuit on a GPIO line: libgpiod 1.6 edge events read by its own thread
// (ThreadRole::kEstop, above every other real-time thread), which runs the reaction on the
// first opening edge. A failed read counts as an opening: the input is monitored, and one
// that cannot be read is not trusted to be closed.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "io/estop_input.hpp"
#include "io/linux/gpio_config.hpp"
#include "io/realtime.hpp"

namespace weedspray::io::hw {

struct GpioEstopInputConfig {
  std::string chip;
  // Logical 1 = circuit closed: active_low when the closed contact pulls the line low.
  GpioLineConfig line;
  // How long the circuit must stay closed to count as closed again.
  std::chrono::nanoseconds closing_hold = std::chrono::milliseconds(50);
  std::string consumer = "weedsprayd";
};

class GpioEstopInput final : public EstopInput {
 public:
  // Requests the line's edge events and reads its level. Throws std::runtime_error naming the
  // chip/line on failure.
  explicit GpioEstopInput(const GpioEstopInputConfig& config);
  ~GpioEstopInput() override;
  GpioEstopInput(const GpioEstopInput&) = delete;
  GpioEstopInput& operator=(const GpioEstopInput&) = delete;

  EstopSample sample() const noexcept override;
  // Starts the edge thread.
  void arm(const EstopReaction& reaction) override;
  void disarm() noexcept override;
  RtStatus thread_status() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace weedspray::io::hw
