// SPDX-License-Identifier: Apache-2.0
// Calibration helpers (SPEC §2-§4): plain structs the config/daemon can persist.
// (1) Flow meter pulses per litre from a catch test: the user runs the line, collects the
//     liquid and weighs/measures it; pulses counted by the meter over the same time.
// (2) Least-squares line q = A s + b per nozzle from (duty %, measured flow L/min) points, with
//     R^2 and a check of the line's validity range (20..80 % by default, wheat paper he2024).
// Pure functions; they throw std::invalid_argument naming the argument on bad input.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "control/spray_rate_law.hpp"

namespace weedspray::control {

struct FlowMeterCalibration {
  double pulses_per_litre = 0.0;             // measured
  double configured_pulses_per_litre = 0.0;  // what the config had
  double error_pct = 0.0;  // (configured - measured) / measured * 100: the config's error
};

// pulses > 0, collected_volume_l > 0, configured_pulses_per_litre > 0.
FlowMeterCalibration calibrate_flow_meter(std::uint64_t pulses, double collected_volume_l,
                                          double configured_pulses_per_litre);

struct DutyFlowPoint {
  double duty_pct = 0.0;
  double flow_l_per_min = 0.0;
};

struct NozzleLineFit {
  NozzleLine line{};
  double r_squared = 0.0;
  std::size_t points_used = 0;      // points inside [valid_min, valid_max]
  std::size_t points_rejected = 0;  // points outside the validity range (not fitted)
  double residual_rms_l_per_min = 0.0;
};

// Fits the points whose duty lies in [valid_min_duty_pct, valid_max_duty_pct]; needs >= 2
// such points with distinct duties (else std::invalid_argument). R^2 = 1 - SSres / SStot
// (1 when all flows are equal and fitted exactly).
NozzleLineFit fit_nozzle_line(std::span<const DutyFlowPoint> points, double pressure_mpa,
                              double valid_min_duty_pct = 20.0, double valid_max_duty_pct = 80.0);

}  // namespace weedspray::control
