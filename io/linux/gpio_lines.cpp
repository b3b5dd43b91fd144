// SPDX-License-Identifier: Apache-2.0
#include "io/linux/gpio_lines.hpp"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <system_error>

namespace weedspray::io::hw::detail {

std::string describe(const std::string& chip, const GpioLineConfig& line) {
  std::string where = chip.empty() ? "any GPIO chip" : "GPIO chip '" + chip + "'";
  if (!line.name.empty()) return "line '" + line.name + "' on " + where;
  return "line offset " + std::to_string(line.offset) + " on " + where;
}

gpiod::chip open_chip(const std::string& chip) {
  try {
    return gpiod::chip(chip, gpiod::chip::OPEN_LOOKUP);
  } catch (const std::system_error& e) {
    throw std::runtime_error("GPIO chip '" + chip + "' not found or not accessible (" +
                             e.code().message() + "); list chips with gpiodetect");
  } catch (const std::exception& e) {
    throw std::runtime_error("GPIO chip '" + chip + "': " + e.what());
  }
}

gpiod::line find_line(const std::string& chip, const GpioLineConfig& config) {
  gpiod::line line;
  if (!config.name.empty()) {
    try {
      line = chip.empty() ? gpiod::find_line(config.name) : open_chip(chip).find_line(config.name);
    } catch (const std::runtime_error&) {
      throw;
    } catch (const std::exception& e) {
      throw std::runtime_error("cannot search " + describe(chip, config) + ": " + e.what());
    }
    if (!line)
      throw std::runtime_error(describe(chip, config) + " not found; list names with gpioinfo");
  } else {
    if (chip.empty())
      throw std::runtime_error("GPIO line offset " + std::to_string(config.offset) +
                               " given without a chip: set the chip or a line name");
    gpiod::chip c = open_chip(chip);
    if (config.offset < 0 || static_cast<unsigned>(config.offset) >= c.num_lines())
      throw std::runtime_error(describe(chip, config) + " does not exist (the chip has " +
                               std::to_string(c.num_lines()) + " lines)");
    line = c.get_line(static_cast<unsigned>(config.offset));
  }
  if (line.is_used()) {
    const std::string consumer = line.consumer();
    throw GpioLineBusy(describe(chip, config) + " is busy (used by '" +
                       (consumer.empty() ? std::string("kernel") : consumer) + "')");
  }
  return line;
}

int poll_timeout_ms(bool change_pending, std::chrono::nanoseconds due, std::chrono::nanoseconds now,
                    int max_ms) noexcept {
  if (!change_pending) return max_ms;
  return static_cast<int>(std::clamp<std::int64_t>((due - now).count() / 1'000'000 + 1, 0, max_ms));
}

std::bitset<32> bias_flags(GpioBias bias) {
  switch (bias) {
    case GpioBias::kAsIs:
      return {};
    case GpioBias::kDisabled:
      return gpiod::line_request::FLAG_BIAS_DISABLE;
    case GpioBias::kPullUp:
      return gpiod::line_request::FLAG_BIAS_PULL_UP;
    case GpioBias::kPullDown:
      return gpiod::line_request::FLAG_BIAS_PULL_DOWN;
  }
  return {};
}

}  // namespace weedspray::io::hw::detail
