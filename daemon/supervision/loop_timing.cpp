// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/loop_timing.hpp"

#include <spdlog/fmt/fmt.h>

#include <string_view>

namespace weedspray::daemon {
namespace {

double us(std::chrono::nanoseconds ns) {
  return static_cast<double>(ns.count()) / 1e3;
}

struct Row {
  std::string_view name;
  const io::LatenessHistogram& histogram;
  LoopTimingCounts counts;
};

template <class F>
void for_each_loop(const TimingReportInput& in, F&& f) {
  const Row rows[] = {{"valve_edges", in.timing->valve_edges, in.valve_edges},
                      {"pressure_loop", in.timing->pressure_loop, in.pressure_loop},
                      {"control_loop", in.timing->control_loop, in.control_loop}};
  for (const Row& row : rows) f(row, io::summarize(row.histogram));
}

}  // namespace

std::string timing_report_line(const TimingReportInput& in) {
  std::string out;
  for_each_loop(in, [&](const Row& row, const io::LatenessSummary& s) {
    if (!out.empty()) out += " | ";
    out += fmt::format("{} p99 {:.0f} us max {:.0f} us ({} misses, {} overruns)", row.name,
                       us(s.p99), us(s.max), row.counts.misses, row.counts.overruns);
  });
  out += fmt::format(" | converter overruns {} | misses while spraying {}", in.converter_overruns,
                     in.misses_while_spraying);
  return out;
}

std::string timing_report_json(const TimingReportInput& in) {
  std::string loops;
  for_each_loop(in, [&](const Row& row, const io::LatenessSummary& s) {
    if (!loops.empty()) loops += ", ";
    loops += fmt::format(
        "\"{}\": {{\"samples\": {}, \"p50_us\": {:.1f}, \"p99_us\": {:.1f}, \"p999_us\": {:.1f}, "
        "\"max_us\": {:.1f}, \"misses\": {}, \"overruns\": {}}}",
        row.name, s.samples, us(s.p50), us(s.p99), us(s.p999), us(s.max), row.counts.misses,
        row.counts.overruns);
  });
  return fmt::format(
      "{{\"seconds\": {:.1f}, \"spraying_seconds\": {:.1f}, \"realtime\": {}, "
      "\"cpu_latency_request\": \"{}\", \"loops\": {{{}}}, \"converter_overruns\": {}, "
      "\"misses_while_spraying\": {}}}",
      in.seconds, in.spraying_seconds, in.realtime ? "true" : "false", in.cpu_latency_request,
      loops, in.converter_overruns, in.misses_while_spraying);
}

}  // namespace weedspray::daemon
