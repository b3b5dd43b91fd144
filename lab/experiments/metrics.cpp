// SPDX-License-Identifier: Apache-2.0
#include "lab/experiments/metrics.hpp"
#include "lab/experiments/vocabulary.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace weedspray::lab::experiments {

StepMetrics step_metrics(std::span<const double> t, std::span<const double> y, double setpoint,
                         double band) {
  if (t.size() != y.size() || t.size() < 2)
    throw std::invalid_argument("step_metrics: times and values must have equal size >= 2");
  StepMetrics m;
  double t10 = -1.0;
  double t90 = -1.0;
  double peak = y[0];
  double last_outside = 0.0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t10 < 0 && y[i] >= 0.1 * setpoint) t10 = t[i];
    if (t90 < 0 && y[i] >= 0.9 * setpoint) t90 = t[i];
    peak = std::max(peak, y[i]);
    if (std::abs(y[i] - setpoint) > band * std::abs(setpoint)) last_outside = t[i];
    if (i > 0) {
      const double dt = t[i] - t[i - 1];
      m.itae +=
          0.5 * (t[i] * std::abs(setpoint - y[i]) + t[i - 1] * std::abs(setpoint - y[i - 1])) * dt;
    }
  }
  m.rise_s = (t10 >= 0 && t90 >= 0) ? t90 - t10 : t.back();
  m.overshoot_pct = std::max(0.0, (peak - setpoint) / setpoint * 100.0);
  m.settled = std::abs(y.back() - setpoint) <= band * std::abs(setpoint);
  m.settle_s = m.settled ? last_outside : t.back();
  return m;
}

LineFit fit_line(std::span<const double> x, std::span<const double> y) {
  if (x.size() != y.size() || x.size() < 2)
    throw std::invalid_argument("fit_line: x and y must have equal size >= 2");
  const double n = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= n;
  my /= n;
  double sxx = 0, sxy = 0, syy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
    syy += (y[i] - my) * (y[i] - my);
  }
  if (sxx <= 0.0) throw std::invalid_argument("fit_line: all x values are equal");
  LineFit f;
  f.slope = sxy / sxx;
  f.intercept = my - f.slope * mx;
  double ss_res = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double r = y[i] - (f.slope * x[i] + f.intercept);
    ss_res += r * r;
  }
  f.r_squared = syy > 0 ? 1.0 - ss_res / syy : 1.0;
  return f;
}

double peak_to_peak(std::span<const double> values) {
  if (values.empty()) return 0.0;
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  return *hi - *lo;
}

}  // namespace weedspray::lab::experiments
