// SPDX-License-Identifier: Apache-2.0
// The owning board's GNSS fix as it travels with its motion sample (docs/fleet.md, "Shared
// speed and position"): where its antenna was, which way it pointed, and when the fix arrived
// on the owning board's clock, so a board without a receiver can age it like the speed.
#pragma once

#include <cmath>
#include <cstdint>

#include "io/gnss.hpp"

namespace weedspray::daemon {

// Trivially copyable: it rides in the shared motion sample's LatestValue slot.
struct SharedFix {
  double latitude_deg = io::GnssFix::kUnknown;
  double longitude_deg = io::GnssFix::kUnknown;
  double heading_deg = io::GnssFix::kUnknown;  // course over ground, from true north, clockwise
  io::GnssFixMode mode = io::GnssFixMode::kNone;
  std::uint64_t sender_time_ns = 0;  // the owning board's clock when the fix arrived there
  std::int64_t utc_ns = 0;           // the receiver's UTC time of the fix (0 = unknown)

  [[nodiscard]] bool has_position() const noexcept {
    return mode != io::GnssFixMode::kNone && std::isfinite(latitude_deg) &&
           std::isfinite(longitude_deg) && latitude_deg >= -90 && latitude_deg <= 90 &&
           longitude_deg >= -180 && longitude_deg <= 180;
  }
};

// The fix mode as gpsd numbers it, on the bus and the motion topic: 2 a 2D fix, 3 a 3D fix,
// 0 none (anything else reads as none).
constexpr std::uint32_t fix_mode_number(io::GnssFixMode mode) noexcept {
  return mode == io::GnssFixMode::k3D ? 3 : mode == io::GnssFixMode::k2D ? 2 : 0;
}
constexpr io::GnssFixMode fix_mode_from_number(std::uint32_t number) noexcept {
  return number == 3   ? io::GnssFixMode::k3D
         : number == 2 ? io::GnssFixMode::k2D
                       : io::GnssFixMode::kNone;
}

}  // namespace weedspray::daemon
