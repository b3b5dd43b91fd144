// SPDX-License-Identifier: Apache-2.0
// Board output lines as the daemon and the fail-safe writer request them (libgpiod, each
// requested at its safe value), kept alive by the Backends that owns them.
#pragma once

#include <memory>
#include <string>

#include "daemon/backends/backends.hpp"

namespace weedspray::daemon {

template <class T>
T* keep(Backends& b, std::shared_ptr<T> device) {
  b.owned.push_back(device);
  return device.get();
}

// A line is wired when the configuration names it or gives its offset.
inline bool wired(const std::string& name, int offset) {
  return !name.empty() || offset >= 0;
}

// One output line (pump, buzzer, LED, heartbeat) as a bank of one, low = safe; null when the
// line is not wired. Throws std::runtime_error naming the chip and line.
io::DigitalOutputBank* single_line(Backends& b, const GpioSection& gpio, const std::string& name,
                                   int offset, bool active_low);

}  // namespace weedspray::daemon
