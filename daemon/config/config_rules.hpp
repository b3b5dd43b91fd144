// SPDX-License-Identifier: Apache-2.0
// The rules between keys of a configuration whose every value parsed: cameras and nozzles,
// GPIO lines used once, trip limits against the sensor, Modbus modules, fleet names. Each
// refusal names the key to blame where it was set (file and line).
#pragma once

#include <string>

#include "daemon/config/config.hpp"

namespace weedspray::daemon {

// Throws ConfigError at `key`, located where the configuration set it (else where it set
// `located_by`, else its last file, line 0).
[[noreturn]] void fail_at_key(const Config& config, const std::string& key,
                              const std::string& message, const std::string& located_by = "");

// A number as the configuration's messages print it (the shortest of %g's form).
std::string format_number(double value);

// Throws the first broken rule as a ConfigError.
void check_config_rules(const Config& config);

}  // namespace weedspray::daemon
