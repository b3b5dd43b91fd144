// SPDX-License-Identifier: Apache-2.0
// Drives the simulated world (vehicle speed, plant) from the test thread until a condition
// holds, as the daemon's main loop would: shared by the sim tests of the Sprayer's loops.
#pragma once

#include <chrono>
#include <thread>

#include "daemon/backends/backends.hpp"

namespace weedspray::daemon {

// Runs the simulated world for up to `limit` until `done()` holds; returns whether it did.
template <class Done>
bool run_until(Backends& backends, Done done, std::chrono::nanoseconds limit) {
  const auto start = backends.clock->now();
  while (backends.clock->now() - start < limit) {
    backends.drive_world(std::chrono::duration<double>(backends.clock->now()).count());
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

}  // namespace weedspray::daemon
