// SPDX-License-Identifier: Apache-2.0
// Internal helpers shared by the libgpiod backends: find a chip and a line from the
// configuration with errors that name what was looked for.
#pragma once

#include <bitset>
#include <chrono>
#include <gpiod.hpp>
#include <stdexcept>
#include <string>

#include "io/linux/gpio_config.hpp"

namespace weedspray::io::hw {

// A line another request still holds (another program, or a daemon whose requests the kernel
// has not released yet): the one GPIO error worth retrying. The message names the line and
// its consumer.
class GpioLineBusy : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace weedspray::io::hw

namespace weedspray::io::hw::detail {

// Opens `chip` by path, name, label or number. Throws std::runtime_error naming it.
gpiod::chip open_chip(const std::string& chip);

// The line `line` names: by name (on `chip` if given, else on any chip) or by offset on
// `chip`. Throws std::runtime_error naming the chip and line; GpioLineBusy when the line is
// already used by another consumer.
gpiod::line find_line(const std::string& chip, const GpioLineConfig& line);

// Human-readable "chip X line Y" for messages.
std::string describe(const std::string& chip, const GpioLineConfig& line);

std::bitset<32> bias_flags(GpioBias bias);

// How long an edge reader may block in poll(): `max_ms`, or less when a debounced change
// becomes due at `due` (rounded up to the next whole ms).
int poll_timeout_ms(bool change_pending, std::chrono::nanoseconds due, std::chrono::nanoseconds now,
                    int max_ms) noexcept;

}  // namespace weedspray::io::hw::detail
