// SPDX-License-Identifier: Apache-2.0
// Which ground speed the rate law uses, and when a GNSS fix counts as lost: pure functions of
// the latest values (no clock of their own), called by the control loop every cycle and by the
// main loop's alarm evaluation.
//
// speed.source = "wheel": the [wheel] speed (its pulses, or wheel.fixed_speed_m_per_s).
//                "gnss":  the receiver's speed over ground while its fix is usable; otherwise
//                         the wheel's pulses when wired, else wheel.fixed_speed_m_per_s.
//                "fixed": wheel.fixed_speed_m_per_s.
//                "fleet": another board's speed while its samples arrive (shared_motion.hpp);
//                         none (0, and the valves held closed) once they stop.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string_view>

#include "io/gnss.hpp"
#include "io/latest_value.hpp"

namespace weedspray::daemon {

enum class SpeedSource : std::uint8_t { kWheel, kGnss, kFixed, kFleet };
std::optional<SpeedSource> parse_speed_source(std::string_view name) noexcept;
// "wheel", "gnss", "fixed", "fleet"
std::string_view to_string(SpeedSource source) noexcept;

using GnssSample = io::Stamped<io::GnssFix>;  // sample_time: when the fix arrived

// A fix the speed may come from: 2D or 3D, a speed given, and arrived within `timeout` of now.
bool gnss_fix_usable(const GnssSample& sample, std::chrono::nanoseconds now,
                     std::chrono::nanoseconds timeout) noexcept;

// The gnss_fix_lost alarm's condition, one update per main-loop tick: no usable fix now, after
// one was usable (lost once it is `timeout` old, at once when the receiver reports no fix), or
// none within `first_fix_timeout` of `start` (a receiver's cold start takes 30-60 s: no alarm
// at every power-on).
class LostFixWatch {
 public:
  LostFixWatch(std::chrono::nanoseconds start, std::chrono::nanoseconds timeout,
               std::chrono::nanoseconds first_fix_timeout) noexcept
      : start_(start), timeout_(timeout), first_fix_timeout_(first_fix_timeout) {}
  bool lost(const GnssSample& latest, std::chrono::nanoseconds now) noexcept;

 private:
  std::chrono::nanoseconds start_, timeout_, first_fix_timeout_;
  bool had_fix_ = false;
};

struct GroundSpeedInputs {
  SpeedSource source = SpeedSource::kWheel;
  bool wheel_wired = false;  // wheel.source = "pulses"
  double wheel_speed_m_per_s = 0;
  double fixed_speed_m_per_s = 0;
  bool gnss_usable = false;  // gnss_fix_usable() of the latest fix
  double gnss_speed_m_per_s = 0;
  bool shared_fresh = false;  // the owning board's latest sample is within its timeout
  double shared_speed_m_per_s = 0;
};

struct GroundSpeed {
  double speed_m_per_s = 0;
  SpeedSource used = SpeedSource::kFixed;  // where it came from this cycle
  bool fell_back = false;  // "gnss" asked, no usable fix; "fleet" asked, its samples stopped
};

GroundSpeed select_ground_speed(const GroundSpeedInputs& in) noexcept;

}  // namespace weedspray::daemon
