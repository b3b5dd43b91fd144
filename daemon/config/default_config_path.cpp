// SPDX-License-Identifier: Apache-2.0
// The installed configuration file's path. Its one define comes from the install prefix
// (daemon/CMakeLists.txt sets it on this file alone, so the rest of the tree compiles the same
// whatever the prefix).
#include "daemon/config/config.hpp"

#ifndef WEEDSPRAY_CONFIG_PATH
#define WEEDSPRAY_CONFIG_PATH "/etc/weedspray/weedspray.toml"
#endif

namespace weedspray::daemon {

const char* const kDefaultConfigPath = WEEDSPRAY_CONFIG_PATH;

}  // namespace weedspray::daemon
