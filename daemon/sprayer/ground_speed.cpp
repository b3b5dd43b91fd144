// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/ground_speed.hpp"

#include <cmath>

namespace weedspray::daemon {

std::optional<SpeedSource> parse_speed_source(std::string_view name) noexcept {
  if (name == "wheel") return SpeedSource::kWheel;
  if (name == "gnss") return SpeedSource::kGnss;
  if (name == "fixed") return SpeedSource::kFixed;
  if (name == "fleet") return SpeedSource::kFleet;
  return std::nullopt;
}

std::string_view to_string(SpeedSource source) noexcept {
  switch (source) {
    case SpeedSource::kWheel:
      return "wheel";
    case SpeedSource::kGnss:
      return "gnss";
    case SpeedSource::kFleet:
      return "fleet";
    case SpeedSource::kFixed:
      break;
  }
  return "fixed";
}

bool gnss_fix_usable(const GnssSample& sample, std::chrono::nanoseconds now,
                     std::chrono::nanoseconds timeout) noexcept {
  const io::GnssFix& fix = sample.value;
  return fix.mode != io::GnssFixMode::kNone && std::isfinite(fix.speed_m_per_s) &&
         fix.speed_m_per_s >= 0 && now - sample.sample_time <= timeout;
}

bool LostFixWatch::lost(const GnssSample& latest, std::chrono::nanoseconds now) noexcept {
  if (gnss_fix_usable(latest, now, timeout_)) {
    had_fix_ = true;
    return false;
  }
  return had_fix_ || now - start_ > first_fix_timeout_;
}

GroundSpeed select_ground_speed(const GroundSpeedInputs& in) noexcept {
  const GroundSpeed wheel_or_fixed =
      in.wheel_wired ? GroundSpeed{in.wheel_speed_m_per_s, SpeedSource::kWheel, false}
                     : GroundSpeed{in.fixed_speed_m_per_s, SpeedSource::kFixed, false};
  switch (in.source) {
    case SpeedSource::kWheel:
      return wheel_or_fixed;
    case SpeedSource::kGnss:
      if (in.gnss_usable) return {in.gnss_speed_m_per_s, SpeedSource::kGnss, false};
      return {wheel_or_fixed.speed_m_per_s, wheel_or_fixed.used, true};
    case SpeedSource::kFleet:
      // No fallback: a board's own wheel or a fixed speed would place its spray off the
      // others'. Standing still holds the plan, and the control loop closes the valves.
      if (in.shared_fresh) return {in.shared_speed_m_per_s, SpeedSource::kFleet, false};
      return {0.0, SpeedSource::kFleet, true};
    case SpeedSource::kFixed:
      break;
  }
  return {in.fixed_speed_m_per_s, SpeedSource::kFixed, false};
}

}  // namespace weedspray::daemon
