// SPDX-License-Identifier: Apache-2.0
// The motion topic's payload (docs/fleet.md): a board's ground speed and odometer with its
// daemon's clock, published by the board that owns the speed and read by those that take it.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string_view>

#include <nlohmann/json.hpp>

namespace weedspray::fleet {

// The owning board's GNSS fix with the sample, while it has a usable one.
struct MotionFix {
  double latitude_deg = 0;
  double longitude_deg = 0;
  double heading_deg = std::numeric_limits<double>::quiet_NaN();  // NaN: not known (standing)
  std::uint32_t mode = 0;     // gpsd's numbers: 2 a 2D fix, 3 a 3D fix, 0 none
  std::uint64_t time_ns = 0;  // when the fix arrived, on the owning daemon's clock
  std::int64_t utc_ns = 0;    // the receiver's UTC time of the fix (0 = unknown)

  [[nodiscard]] bool present() const noexcept { return mode == 2 || mode == 3; }
};

struct MotionSample {
  double speed_m_per_s = 0;
  double distance_m = 0;
  std::uint64_t time_ns = 0;  // the owning daemon's clock (its control cycle), no shared epoch
  MotionFix fix;              // mode 0: the owning board has no usable fix
};

// {"m_per_s", "distance_m", "t_ns"}, and with a fix also {"lat", "lon", "heading_deg" (when
// known), "fix" (2 or 3), "fix_t_ns", "utc_ns" (when known)}.
[[nodiscard]] nlohmann::json motion_payload(const MotionSample& sample);

// The sample, or nothing when the payload is not such an object (a number missing, negative
// speed or time, not finite). A fix that is absent, of mode 0 or incomplete leaves the sample
// without one (an owner that shares no position still shares its speed).
[[nodiscard]] std::optional<MotionSample> parse_motion(std::string_view payload);

}  // namespace weedspray::fleet
