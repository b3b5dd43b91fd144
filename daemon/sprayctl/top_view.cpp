// SPDX-License-Identifier: Apache-2.0
// `sprayctl top`: a live terminal view of one board.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <thread>

#include "daemon/sprayctl/value_text.hpp"
#include "daemon/sprayctl/views.hpp"

namespace weedspray::sprayctl {

namespace {

constexpr int kBarWidth = 30;

double number(const Properties& p, const char* name) {
  const auto found = p.find(name);
  return found != p.end() && found->second.is_number() ? found->second.get<double>() : NAN;
}

std::string text(const Properties& p, const char* name) {
  const auto found = p.find(name);
  return found == p.end() ? std::string("?") : text_value(name, found->second);
}

const Value& list(const Properties& p, const char* name) {
  static const Value empty = Value::array();
  const auto found = p.find(name);
  return found != p.end() && found->second.is_array() ? found->second : empty;
}

std::string fixed(double x, int decimals) {
  if (!std::isfinite(x)) return "-";
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals)
      << (std::abs(x) < 0.5 * std::pow(10, -decimals) ? 0.0 : x);
  return out.str();
}

std::string bar(double percent) {
  const double clamped = std::isfinite(percent) ? std::clamp(percent, 0.0, 100.0) : 0.0;
  const int filled = static_cast<int>(std::lround(clamped / 100.0 * kBarWidth));
  std::string text = "[";
  text.append(static_cast<std::size_t>(filled), '#');
  text.append(static_cast<std::size_t>(kBarWidth - filled), ' ');
  text += ']';
  return text;
}

}  // namespace

std::string top_frame(const Properties& p, std::chrono::system_clock::time_point now) {
  std::ostringstream out;
  out << "weedsprayd  " << text(p, "State") << " (" << text(p, "Mode") << ")   "
      << local_time_of_day(now).substr(0, 8) << "   Ctrl-C quits\n";
  out << "Pressure " << fixed(number(p, "Pressure"), 2) << " / "
      << fixed(number(p, "PressureSetpoint"), 2) << " MPa   Flow " << fixed(number(p, "Flow"), 2)
      << " L/min   Speed " << fixed(number(p, "Speed"), 2) << " m/s (" << text(p, "SpeedSource")
      << ")   Tank " << fixed(number(p, "TankLevel"), 0) << " %\n";
  // The dose over the job so far: the litres sprayed over the area the boom covered.
  const double area_m2 = number(p, "AreaCovered");
  const double volume_l = number(p, "VolumeSprayed");
  const double rate_now = number(p, "ApplicationRate");
  out << "Rate     " << (std::isfinite(rate_now) ? fixed(rate_now, 1) : "-")
      << " L/ha now over the boom (" << fixed(number(p, "TargetRate"), 0)
      << " L/ha at full weed cover)\n";
  out << "Applied  " << (area_m2 > 0 ? fixed(volume_l / area_m2 * 10000.0, 1) : "-")
      << " L/ha over the job (" << fixed(volume_l, 2) << " L on " << fixed(area_m2, 0)
      << " m^2)   saving " << fixed(number(p, "SavingsPercent"), 0) << " %\n";
  out << "Vision   " << fixed(number(p, "FrameRate"), 1) << " fps, latency "
      << fixed(number(p, "VisionLatencyMs"), 0) << " ms (p99 "
      << fixed(number(p, "VisionLatencyP99Ms"), 0) << " ms)   overruns "
      << text(p, "ControlOverruns") << "\n";
  const Value& duties = list(p, "NozzleDuty");
  const Value& health = list(p, "NozzleHealth");
  out << "Nozzle   duty" << std::string(kBarWidth - 2, ' ') << "health (flow / baseline)\n";
  for (std::size_t i = 0; i < duties.size(); ++i) {
    const double duty = duties[i].is_number() ? duties[i].get<double>() : NAN;
    const double h = i < health.size() && health[i].is_number() ? health[i].get<double>() : NAN;
    out << std::setw(4) << i << "    " << bar(duty) << std::setw(5) << fixed(duty, 0) << " %  "
        << (std::isfinite(h) ? fixed(h, 2) : std::string("off")) << "\n";
  }
  const Value& alarms = list(p, "AlarmDetails");
  out << "Alarms   " << (alarms.empty() ? "none" : "") << "\n";
  for (const auto& alarm : alarms) {
    out << "  " << (alarm.value("present", false) ? "ACTIVE " : "latched") << " "
        << alarm.value("name", "") << " (" << alarm.value("severity", "")
        << "): " << alarm.value("remedy", "") << "\n";
  }
  return out.str();
}

int run_top(BusClient& client, double interval_s, int frames) {
  static volatile std::sig_atomic_t stop = 0;
  std::signal(SIGINT, [](int) { stop = 1; });
  std::signal(SIGTERM, [](int) { stop = 1; });
  // On a terminal each frame replaces the last; into a file or a pipe they follow each other.
  const bool terminal = ::isatty(STDOUT_FILENO) != 0;
  const auto period = std::chrono::duration<double>(interval_s);
  auto next = std::chrono::steady_clock::now();
  for (int shown = 0; !stop && (frames == 0 || shown < frames); ++shown) {
    const std::string frame = top_frame(client.get_all(), std::chrono::system_clock::now());
    std::cout << (terminal ? "\033[H\033[2J" : (shown ? "\n" : "")) << frame << std::flush;
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    if (frames == 0 || shown + 1 < frames) std::this_thread::sleep_until(next);
  }
  return 0;
}

}  // namespace weedspray::sprayctl
