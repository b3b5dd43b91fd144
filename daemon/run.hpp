// SPDX-License-Identifier: Apache-2.0
// The daemon proper: backends, threads, D-Bus, until a signal. Returns the exit status.
#pragma once

#include "daemon/config/options.hpp"

namespace weedspray::daemon {

int run_daemon(const Options& options);
// weedsprayd --safe-outputs: every configured output at its safe value, then exit (0, or 1 when
// any output could not be written, each named on stderr).
int write_safe_outputs(const Options& options);

}  // namespace weedspray::daemon
