// SPDX-License-Identifier: Apache-2.0
#pragma once

// The experiments run the daemon's control code on the plant model: both are named unqualified
// in lab::experiments, as they were written.
namespace weedspray::control {}
namespace weedspray::sim::plant {}

namespace weedspray::lab::experiments {
using namespace weedspray::control;  // NOLINT(google-build-using-namespace)
namespace plant = weedspray::sim::plant;
}  // namespace weedspray::lab::experiments
