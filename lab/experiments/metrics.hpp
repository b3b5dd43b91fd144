// SPDX-License-Identifier: Apache-2.0
// Figures of merit the experiments report: step-response metrics and line fits.
#pragma once

#include <span>

namespace weedspray::lab::experiments {

struct StepMetrics {
  double rise_s = 0.0;         // 10 % -> 90 % of the set-point (first crossing)
  double overshoot_pct = 0.0;  // (peak - set-point) / set-point * 100, 0 if never above
  double settle_s = 0.0;       // last time outside +-band, measured from the step (t = 0)
  double itae = 0.0;           // integral of t |e(t)| dt [MPa s^2]
  bool settled = false;        // inside the band at the end of the record
};

// times_s ascending from the step at t = 0; values the controlled variable.
StepMetrics step_metrics(std::span<const double> times_s, std::span<const double> values,
                         double setpoint, double settle_band_fraction = 0.02);

// Least-squares line y = slope x + intercept and its coefficient of determination.
struct LineFit {
  double slope = 0.0;
  double intercept = 0.0;
  double r_squared = 0.0;
};
// Needs >= 2 points with distinct x; throws std::invalid_argument otherwise.
LineFit fit_line(std::span<const double> x, std::span<const double> y);

// Peak-to-peak of values.
double peak_to_peak(std::span<const double> values);

}  // namespace weedspray::lab::experiments
