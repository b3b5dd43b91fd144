// The daemon proper: backends, threads, D-Bus, until a signal. Returns the exit status.
#pragma once

#include "daemon/options.hpp"

namespace weedspray::daemon {

int run_daemon(const Options& options);

}  // namespace weedspray::daemon
