// SPDX-License-Identifier: Apache-2.0
// A debounced DigitalInput (the start/stop key) on libgpiod 1.6 edge events, read by its own
// thread (ThreadRole::kDigitalInput).
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "io/digital_input.hpp"
#include "io/linux/gpio_config.hpp"
#include "io/realtime.hpp"

namespace weedspray::io::hw {

struct GpioDigitalInputConfig {
  std::string chip;
  GpioLineConfig line;
  GpioBias bias = GpioBias::kAsIs;
  std::chrono::nanoseconds debounce = std::chrono::milliseconds(30);
  std::string consumer = "weedsprayd";
};

class GpioDigitalInput final : public DigitalInput {
 public:
  // Throws std::runtime_error naming the chip/line on failure.
  explicit GpioDigitalInput(const GpioDigitalInputConfig& config);
  ~GpioDigitalInput() override;
  GpioDigitalInput(const GpioDigitalInput&) = delete;
  GpioDigitalInput& operator=(const GpioDigitalInput&) = delete;

  DigitalInputSample sample() const noexcept override;
  RtStatus thread_status() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace weedspray::io::hw
