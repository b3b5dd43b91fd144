// SPDX-License-Identifier: Apache-2.0
// How GPIO lines are named in the configuration: by chip + offset, or by line name.
#pragma once

#include <string>
#include <vector>

namespace weedspray::io::hw {

struct GpioLineConfig {
  // A line name (as in the device tree / gpio-line-names); searched with gpiod::find_line.
  // When empty, `offset` on the bank's chip is used.
  std::string name;
  int offset = -1;
  bool active_low = false;
  bool safe_value = false;  // logical value for force_safe() and the request's default
};

enum class GpioBias { kAsIs, kDisabled, kPullUp, kPullDown };

}  // namespace weedspray::io::hw
