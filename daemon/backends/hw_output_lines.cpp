// SPDX-License-Identifier: Apache-2.0
#include "daemon/backends/hw_output_lines.hpp"

#include "io/linux/gpio_output_bank.hpp"

namespace weedspray::daemon {

io::DigitalOutputBank* single_line(Backends& b, const GpioSection& gpio, const std::string& name,
                                   int offset, bool active_low) {
  if (!wired(name, offset)) return nullptr;
  io::hw::GpioOutputBankConfig config;
  config.chip = gpio.chip;
  config.lines.push_back(io::hw::GpioLineConfig{
      .name = name, .offset = offset, .active_low = active_low, .safe_value = false});
  return keep(b, std::make_shared<io::hw::GpioOutputBank>(config));
}

}  // namespace weedspray::daemon
