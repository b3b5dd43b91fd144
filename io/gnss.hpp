// SPDX-License-Identifier: Apache-2.0
// GNSS position, speed and course (a receiver behind gpsd: NMEA over serial/USB, u-blox, RTK).
// A receiver read blocks for up to its wait: only ever on a worker thread, which publishes each
// fix into a LatestValue<Stamped<GnssFix>> (sample_time: when it arrived, on the daemon's
// clock) for the control loop and the main loop to read wait-free.
#pragma once

#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string_view>

namespace weedspray::io {

enum class GnssFixMode : std::uint8_t { kNone, k2D, k3D };

constexpr std::string_view to_string(GnssFixMode mode) noexcept {
  return mode == GnssFixMode::k3D ? "3d" : mode == GnssFixMode::k2D ? "2d" : "none";
}

// One position report. NaN: the receiver did not give that value with this fix.
struct GnssFix {
  static constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
  std::int64_t utc_ns = 0;  // the receiver's UTC time of the fix, since 1970 (0 = unknown)
  double latitude_deg = kUnknown;
  double longitude_deg = kUnknown;
  double altitude_m = kUnknown;  // above mean sea level
  double speed_m_per_s = kUnknown;
  double course_deg = kUnknown;  // over ground, from true north, clockwise
  double hdop = kUnknown;        // horizontal dilution of precision
  double eph_m = kUnknown;       // estimated horizontal position error (95 %)
  std::uint32_t satellites_used = 0;
  GnssFixMode mode = GnssFixMode::kNone;

  bool has_position() const noexcept {
    return mode != GnssFixMode::kNone && std::isfinite(latitude_deg) &&
           std::isfinite(longitude_deg);
  }
};

// The receiver link's counters (cumulative).
struct GnssLinkStats {
  bool connected = false;
  std::uint64_t fixes = 0;             // position reports received
  std::uint64_t connects = 0;          // successful connections to the source
  std::uint64_t connect_failures = 0;  // attempts refused (source not running, wrong port)
  std::uint64_t disconnects = 0;       // the source went away, or sent what could not be read
};

class GnssReceiver {
 public:
  virtual ~GnssReceiver() = default;
  // Waits up to `wait` for the next position report; true with `fix` filled when one came.
  // Never throws; (re)connects by itself, with a backoff, while the source is away.
  virtual bool next_fix(GnssFix& fix, std::chrono::nanoseconds wait) noexcept = 0;
  virtual GnssLinkStats stats() const noexcept = 0;
};

}  // namespace weedspray::io
