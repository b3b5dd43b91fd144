// SPDX-License-Identifier: Apache-2.0
// One nozzle at one duty over a spray run (linearity, orthogonal): asked for against
// delivered, as a table row.
#pragma once

#include <vector>

#include "lab/experiments/experiments.hpp"
#include "lab/report/report.hpp"

namespace weedspray::lab {

// What a spray run (SprayRunOptions::raw) had on.
inline const char* spray_run_mode(bool raw) {
  return raw ? "RAW: no calibration/compensation/feedback, synchronous"
             : "calibrated, compensated, flow feedback, staggered";
}

inline Table duty_point_table() {
  return Table({{"duty_pct", "duty%", 6, "%6.0f", "%.1f"},
                {"commanded_duty_pct", "commanded%", 10, "%10.2f", "%.3f"},
                {"requested_l", "requested_L", 12, "%12.5f", "%.6f"},
                {"delivered_l", "delivered_L", 12, "%12.5f", "%.6f"},
                {"error_pct", "error%", 8, "%8.2f", "%.4f"}});
}

inline std::vector<Cell> duty_point_cells(const lab::experiments::DutyPoint& p) {
  return {p.duty_pct, p.commanded_duty_pct, p.requested_l, p.delivered_l, p.error_pct};
}

}  // namespace weedspray::lab
