// SPDX-License-Identifier: Apache-2.0
// A DigitalOutputBank on libgpiod 1.6: all lines requested together as one gpiod::line_bulk,
// with the request's default values = the safe values so no valve glitches open at start-up;
// write() sets every line with one set_values() call.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "io/digital_output.hpp"
#include "io/linux/gpio_config.hpp"

namespace weedspray::io::hw {

struct GpioOutputBankConfig {
  // "/dev/gpiochip0", "gpiochip0", or a chip label ("gpio-sim.0-node0", "pinctrl-bcm2711").
  // May be empty when every line is given by name.
  std::string chip;
  std::vector<GpioLineConfig> lines;  // 1..32 lines, all on one chip
  std::string consumer = "weedsprayd";
};

class GpioOutputBank final : public DigitalOutputBank {
 public:
  // Requests the lines. Throws std::runtime_error naming the chip/line on failure (chip not
  // found, line not found, line busy, lines on different chips, too many lines).
  explicit GpioOutputBank(const GpioOutputBankConfig& config);
  ~GpioOutputBank() override;  // force_safe(), then release
  GpioOutputBank(const GpioOutputBank&) = delete;
  GpioOutputBank& operator=(const GpioOutputBank&) = delete;

  std::size_t size() const noexcept override;
  int write(std::uint32_t mask) noexcept override;
  int force_safe() noexcept override;
  std::string describe() const override;
  std::uint32_t safe_mask() const noexcept override;
  // GPIOHANDLE_SET_LINE_VALUES on the line handle libgpiod holds, with the safe values.
  bool emergency_write(EmergencyWrite& out) const noexcept override;

  // The chip the lines were found on (e.g. "gpiochip1") and their offsets, for diagnostics.
  std::string chip_name() const;
  std::vector<unsigned int> offsets() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace weedspray::io::hw
