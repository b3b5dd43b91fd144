// SPDX-License-Identifier: Apache-2.0
// The inputs as the hardware gives them, for commissioning (sprayctl inputs): sensor current,
// pulse counts, contacts. Only what is wired is listed.
#pragma once

#include <vector>

#include "daemon/backends/backends.hpp"
#include "daemon/bus/status.hpp"
#include "daemon/sprayer/runtime_types.hpp"
#include "io/tank_level.hpp"

namespace weedspray::daemon {

std::vector<RawInput> raw_inputs(const Backends& backends, const PressureStatus& pressure,
                                 const io::TankLevelSample& tank);

}  // namespace weedspray::daemon
