// SPDX-License-Identifier: Apache-2.0
// Seconds <-> the loops' nanosecond clock times, for the sprayer's thread bodies.
#pragma once

#include <chrono>
#include <cstdint>

namespace weedspray::daemon::loop_time {

inline double seconds(std::chrono::nanoseconds t) {
  return std::chrono::duration<double>(t).count();
}
inline std::chrono::nanoseconds from_seconds(double s) {
  return std::chrono::nanoseconds(static_cast<std::int64_t>(s * 1e9));
}

}  // namespace weedspray::daemon::loop_time
