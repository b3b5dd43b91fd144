// SPDX-License-Identifier: Apache-2.0
// The motion topic's payload (docs/fleet.md): a board's ground speed and odometer with its
// daemon's clock, published by the board that owns the speed and read by those that take it.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include <nlohmann/json.hpp>

namespace weedspray::fleet {

struct MotionSample {
  double speed_m_per_s = 0;
  double distance_m = 0;
  std::uint64_t time_ns = 0;  // the owning daemon's clock (its control cycle), no shared epoch
};

// {"m_per_s", "distance_m", "t_ns"}
[[nodiscard]] nlohmann::json motion_payload(const MotionSample& sample);

// The sample, or nothing when the payload is not such an object (a number missing, negative
// speed or time, not finite).
[[nodiscard]] std::optional<MotionSample> parse_motion(std::string_view payload);

}  // namespace weedspray::fleet
