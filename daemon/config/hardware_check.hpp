// SPDX-License-Identifier: Apache-2.0
// What hardware mode needs before the daemon starts, checked by `weedsprayd --check-config
// --hardware`: the keys it requires (valve lines, the heartbeat and the E-stop input or their
// opt-outs, the wheel line when speed comes from pulses) and that every device the configuration
// names exists (GPIO chip, cameras, serial ports, IIO converters, the flow counter). Every problem
// is reported, each located at its key.
#pragma once

#include <filesystem>
#include <vector>

#include "daemon/config/config.hpp"

namespace weedspray::daemon {

// Where /dev and /sys are looked for (a test's tree instead of the machine's).
struct DeviceRoots {
  std::filesystem::path dev = "/dev";
  std::filesystem::path sys = "/sys";
};

// Each problem as a ConfigError at the key that would fix it (its file:line when set there,
// else its section's, else the first configuration file's). Empty when hardware mode can start.
std::vector<ConfigError> check_hardware(const Config& config, const DeviceRoots& roots = {});

}  // namespace weedspray::daemon
