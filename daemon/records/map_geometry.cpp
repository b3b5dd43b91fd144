// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/map_geometry.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <numbers>

namespace weedspray::daemon {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

double radians(double deg) {
  return deg / kDegPerRad;
}

// Reads exactly `digits` decimal digits at text[pos]; advances pos.
bool read_digits(std::string_view text, std::size_t& pos, std::size_t digits, int& out) {
  if (pos + digits > text.size()) return false;
  const char* first = text.data() + pos;
  const auto [end, ec] = std::from_chars(first, first + digits, out);
  if (ec != std::errc() || end != first + digits) return false;
  pos += digits;
  return true;
}

bool expect(std::string_view text, std::size_t& pos, char c) {
  if (pos >= text.size() || text[pos] != c) return false;
  ++pos;
  return true;
}

}  // namespace

LatLon step(LatLon from, double north_m, double east_m) {
  const double lat = from.latitude_deg + north_m / kEarthMeanRadiusM * kDegPerRad;
  const double lon =
      from.longitude_deg +
      east_m / (kEarthMeanRadiusM * std::cos(radians(from.latitude_deg))) * kDegPerRad;
  return {lat, lon};
}

void local_offset(LatLon origin, LatLon to, double& north_m, double& east_m) {
  north_m = radians(to.latitude_deg - origin.latitude_deg) * kEarthMeanRadiusM;
  east_m = radians(to.longitude_deg - origin.longitude_deg) * kEarthMeanRadiusM *
           std::cos(radians(origin.latitude_deg));
}

std::optional<LatLon> antenna_at(const io::GnssFix& fix, double ahead_s) {
  if (!fix.has_position()) return std::nullopt;
  const LatLon at{fix.latitude_deg, fix.longitude_deg};
  if (!std::isfinite(fix.speed_m_per_s) || !std::isfinite(fix.course_deg)) return at;
  const double d = fix.speed_m_per_s * ahead_s;
  return step(at, d * std::cos(radians(fix.course_deg)), d * std::sin(radians(fix.course_deg)));
}

LatLon nozzle_patch(LatLon antenna, double heading_deg, const AntennaMount& mount,
                    double nozzle_right_offset_m) {
  // Forward (north, east) = (cos h, sin h); right of it (h + 90 deg) = (-sin h, cos h).
  const double fn = std::cos(radians(heading_deg));
  const double fe = std::sin(radians(heading_deg));
  const double ahead = -mount.ahead_of_nozzles_m;
  const double right = nozzle_right_offset_m - mount.right_of_centre_m;
  return step(antenna, ahead * fn - right * fe, ahead * fe + right * fn);
}

double rate_l_per_ha(double flow_l_per_min, double speed_m_per_s, double width_m) {
  if (!(flow_l_per_min > 0) || !(speed_m_per_s > 0) || !(width_m > 0)) return 0;
  return flow_l_per_min / 60.0 / (speed_m_per_s * width_m) * 10000.0;
}

std::size_t format_utc_ms(std::int64_t utc_ns, char* out, std::size_t size) {
  const std::int64_t ms_total =
      utc_ns >= 0 ? utc_ns / 1'000'000 : -((-utc_ns + 999'999) / 1'000'000);
  std::int64_t seconds = ms_total / 1000;
  int ms = static_cast<int>(ms_total % 1000);
  if (ms < 0) {
    ms += 1000;
    --seconds;
  }
  const std::time_t t = static_cast<std::time_t>(seconds);
  std::tm utc{};
  gmtime_r(&t, &utc);
  const int n = std::snprintf(out, size, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", utc.tm_year + 1900,
                              utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec, ms);
  return n > 0 ? std::min(static_cast<std::size_t>(n), size - 1) : 0;
}

std::string format_utc_ms(std::int64_t utc_ns) {
  char text[40];
  return std::string(text, format_utc_ms(utc_ns, text, sizeof text));
}

std::optional<std::int64_t> parse_utc(std::string_view text) {
  if (!text.empty() && text.back() == 'Z') text.remove_suffix(1);
  std::tm tm{};
  std::size_t pos = 0;
  int year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0;
  std::int64_t fraction_ns = 0;
  if (!read_digits(text, pos, 4, year) || !expect(text, pos, '-') ||
      !read_digits(text, pos, 2, month) || !expect(text, pos, '-') ||
      !read_digits(text, pos, 2, day))
    return std::nullopt;
  if (pos < text.size()) {
    if (!expect(text, pos, 'T') || !read_digits(text, pos, 2, hour) || !expect(text, pos, ':') ||
        !read_digits(text, pos, 2, minute))
      return std::nullopt;
    if (pos < text.size()) {
      if (!expect(text, pos, ':') || !read_digits(text, pos, 2, second)) return std::nullopt;
      if (pos < text.size()) {
        if (!expect(text, pos, '.') || pos >= text.size()) return std::nullopt;
        std::int64_t scale = 100'000'000;
        for (; pos < text.size(); ++pos, scale /= 10) {
          if (text[pos] < '0' || text[pos] > '9') return std::nullopt;
          fraction_ns += (text[pos] - '0') * scale;
        }
      }
    }
  }
  if (month < 1 || month > 12 || day < 1 || day > 31 || hour > 23 || minute > 59 || second > 60)
    return std::nullopt;
  tm.tm_year = year - 1900;
  tm.tm_mon = month - 1;
  tm.tm_mday = day;
  tm.tm_hour = hour;
  tm.tm_min = minute;
  tm.tm_sec = second;
  return static_cast<std::int64_t>(timegm(&tm)) * 1'000'000'000 + fraction_ns;
}

}  // namespace weedspray::daemon
