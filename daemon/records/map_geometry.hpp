// SPDX-License-Identifier: Apache-2.0
// Where a record happened on the Earth: the antenna's fix carried forward to the record's time,
// each nozzle's patch placed from it, UTC text, and a nozzle's rate per hectare. Pure maths
// (no I/O, clocks or threads), shared by the as-applied writer and the map export.
//
// Positions are stepped in a local tangent plane: north/east metres <-> degrees with the
// equirectangular approximation about the point stepped from (a sphere of the WGS84 mean
// radius). Over the few metres between antenna and nozzles, or a 2 m map cell, its error is
// far below a millimetre (it grows with the square of the distance, ~1e-7 of it at 100 m);
// only whole-field distances would need a real projection.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "io/gnss.hpp"

namespace weedspray::daemon {

inline constexpr double kEarthMeanRadiusM = 6371008.8;

struct LatLon {
  double latitude_deg = 0;
  double longitude_deg = 0;
};

// `from` moved north_m north and east_m east (equirectangular step, see above).
LatLon step(LatLon from, double north_m, double east_m);
// The north/east metres from `origin` to `to` (the inverse of step about `origin`).
void local_offset(LatLon origin, LatLon to, double& north_m, double& east_m);

// The antenna's position `ahead_s` seconds after the fix (negative: before), moved in a
// straight line along the fix's course at its speed; the fix itself when either is unknown.
// std::nullopt when the fix has no position.
std::optional<LatLon> antenna_at(const io::GnssFix& fix, double ahead_s);

// Where the antenna sits on the machine (config [gnss]): ahead of the nozzle line along the
// direction of travel, and right of the boom's centre looking forward.
struct AntennaMount {
  double ahead_of_nozzles_m = 0;
  double right_of_centre_m = 0;
};

// The centre of a nozzle's patch on the ground: the antenna's position minus its mount offsets,
// plus the nozzle's own offset right of the boom's centre (nozzle_right_offset_m), all turned
// by the heading (degrees from true north, clockwise).
LatLon nozzle_patch(LatLon antenna, double heading_deg, const AntennaMount& mount,
                    double nozzle_right_offset_m);

// Litres per hectare a nozzle lays on its strip: flow / (ground speed x strip width). 0 when
// closed (no flow) or standing (no speed: the rate is not defined, and nothing is covered).
double rate_l_per_ha(double flow_l_per_min, double speed_m_per_s, double width_m);

// ISO 8601 UTC with milliseconds, "2026-06-24T14:30:01.250Z". `out` holds at least 25 bytes;
// returns the characters written (without the terminating 0).
std::size_t format_utc_ms(std::int64_t utc_ns, char* out, std::size_t size);
std::string format_utc_ms(std::int64_t utc_ns);
// Reads "YYYY-MM-DD", "YYYY-MM-DDTHH:MM[:SS[.fff]]" with an optional "Z" (UTC; no other zone).
// std::nullopt when the text is none of these.
std::optional<std::int64_t> parse_utc(std::string_view text);

}  // namespace weedspray::daemon
