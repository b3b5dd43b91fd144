// SPDX-License-Identifier: Apache-2.0
// What the daemon keeps in RAM: the program and the libraries its real-time loops run are read
// in and locked at start; the libraries only the vision thread runs stay pageable
// (io/linux/memory_lock.hpp says how).
#pragma once

#include <span>
#include <string_view>

namespace weedspray::daemon {

// File-name prefixes of the libraries left pageable: OpenCV and what it pulls in (BLAS/LAPACK,
// protobuf for the DNN importer, TBB, the X11/GL libraries its core links), and the image
// codecs of the simulated camera and the live view. A page of them read back from storage
// delays a frame or a snapshot, never a valve, the pump or the pressure loop.
std::span<const std::string_view> pageable_libraries() noexcept;

// Locks as above and logs what it did; unprivileged (EPERM) it says so and carries on.
void lock_what_the_loops_run();

}  // namespace weedspray::daemon
