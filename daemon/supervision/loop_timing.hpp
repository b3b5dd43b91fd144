// SPDX-License-Identifier: Apache-2.0
// How late each real-time loop of the Sprayer runs: the histograms the loops record into, and
// the timing report (log line, JSON) that `weedsprayd --timing-report` and
// tools/rt-timing.sh print. Misses are lateness beyond alarms.timing_tolerance_ms, the figure
// behind control_overruns; overruns are whole periods lost.
#pragma once

#include <cstdint>
#include <string>

#include "io/lateness_histogram.hpp"

namespace weedspray::daemon {

struct LoopTiming {
  io::LatenessHistogram valve_edges;    // edge written vs. its scheduled time
  io::LatenessHistogram pressure_loop;  // wake vs. deadline
  io::LatenessHistogram control_loop;   // wake vs. deadline
};

// One loop's line of the report.
struct LoopTimingCounts {
  std::uint64_t overruns = 0;  // periods lost (valve edges: edges skipped)
  std::uint64_t misses = 0;    // later than the tolerance
};

struct TimingReportInput {
  const LoopTiming* timing = nullptr;
  LoopTimingCounts valve_edges;
  LoopTimingCounts pressure_loop;
  LoopTimingCounts control_loop;
  std::uint64_t converter_overruns = 0;
  std::uint64_t misses_while_spraying = 0;
  double seconds = 0;               // how long the loops ran
  double spraying_seconds = 0;      // of which spraying
  bool realtime = false;            // every loop got SCHED_FIFO
  std::string cpu_latency_request;  // "0 us" / "none" / why it failed
};

// One line for the log: "valve edges p99 95 us max 679 us (0 misses) | ...".
std::string timing_report_line(const TimingReportInput& in);
// A JSON object (one line).
std::string timing_report_json(const TimingReportInput& in);

}  // namespace weedspray::daemon
