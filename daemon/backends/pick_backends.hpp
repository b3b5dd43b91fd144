// SPDX-License-Identifier: Apache-2.0
// The one choice between the board and the simulation: the backends, their outputs' fatal-exit
// safe writes registered, and the driver of the world around them (a no-op on the board).
#pragma once

#include <memory>

#include "daemon/backends/backends.hpp"
#include "daemon/backends/world_driver.hpp"
#include "daemon/config/config.hpp"
#include "daemon/config/options.hpp"

namespace weedspray::daemon {

// Fills `backends` (kept by the caller: the driver and the sprayer refer to it).
std::unique_ptr<WorldDriver> pick_backends(const Config& config, const Options& options,
                                           Backends& backends);

}  // namespace weedspray::daemon
