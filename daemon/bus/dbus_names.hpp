// SPDX-License-Identifier: Apache-2.0
// The D-Bus names shared by weedsprayd and sprayctl.
#pragma once

namespace weedspray::daemon {

inline constexpr const char* kBusName = "org.weedspray.Sprayer1";
inline constexpr const char* kObjectPath = "/org/weedspray/Sprayer1";
inline constexpr const char* kInterface = "org.weedspray.Sprayer1";

}  // namespace weedspray::daemon
