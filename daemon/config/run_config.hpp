// SPDX-License-Identifier: Apache-2.0
// The configuration a run uses: the files with the command line's overrides. A simulation
// needs no file (every key has a default) and keeps its records apart from the sprayer's; the
// board must have its safety wiring (or its opt-out, warned about).
#pragma once

#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/config/options.hpp"

namespace weedspray::daemon {

// Throws ConfigError (at start, and for each reload).
Config load_config_with_overrides(const Options& options);

struct RunConfig {
  Config config;
  std::vector<std::string> warnings;  // opt-outs that let the board start without a safeguard
  std::string note;                   // where the configuration came from, when worth saying
};

// At start: load_config_with_overrides() and the checks of the board's wiring. Throws
// ConfigError.
RunConfig load_run_config(const Options& options);

}  // namespace weedspray::daemon
