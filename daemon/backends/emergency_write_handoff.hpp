// SPDX-License-Identifier: Apache-2.0
// The daemon hands its fatal-exit safe writes (io/emergency_outputs.hpp: one ioctl or pwrite
// on a descriptor it holds, per output) to its exit watcher over their shared unix socket, each
// with a copy of its descriptor (SCM_RIGHTS). The watcher can then write every output safe the
// moment the daemon starts to die, instead of waiting until the kernel has torn the daemon
// down and released its line requests (daemon/backends/safe_outputs_watch.hpp).
#pragma once

#include "io/emergency_outputs.hpp"

namespace weedspray::daemon {

// Sends every registered write, one message each (the socket must be SOCK_SEQPACKET). Returns
// how many were sent, or -errno at the first that failed.
int hand_emergency_writes(int socket_fd) noexcept;

// Receives one message: 1 with `out` whose fd is this process's copy of the descriptor, 0 at
// end-of-file (the other end is closed: the daemon's process has ended), -errno on error, and
// -EBADMSG for a message that is not one write with one descriptor.
int receive_emergency_write(int socket_fd, io::EmergencyWrite& out) noexcept;

}  // namespace weedspray::daemon
