// SPDX-License-Identifier: Apache-2.0
#include "control/calibration.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace weedspray::control {

FlowMeterCalibration calibrate_flow_meter(std::uint64_t pulses, double collected_volume_l,
                                          double configured_pulses_per_litre) {
  if (pulses == 0) throw std::invalid_argument("flow meter calibration: pulses must be > 0");
  if (!std::isfinite(collected_volume_l) || collected_volume_l <= 0.0) {
    throw std::invalid_argument("flow meter calibration: collected_volume_l must be > 0");
  }
  if (!std::isfinite(configured_pulses_per_litre) || configured_pulses_per_litre <= 0.0) {
    throw std::invalid_argument("flow meter calibration: configured_pulses_per_litre must be > 0");
  }
  FlowMeterCalibration result;
  result.pulses_per_litre = static_cast<double>(pulses) / collected_volume_l;
  result.configured_pulses_per_litre = configured_pulses_per_litre;
  result.error_pct =
      (configured_pulses_per_litre - result.pulses_per_litre) / result.pulses_per_litre * 100.0;
  return result;
}

// Ordinary least squares on two parameters: closed form, no library needed.
NozzleLineFit fit_nozzle_line(std::span<const DutyFlowPoint> points, double pressure_mpa,
                              double valid_min_duty_pct, double valid_max_duty_pct) {
  if (!std::isfinite(pressure_mpa) || pressure_mpa <= 0.0) {
    throw std::invalid_argument("nozzle line fit: pressure_mpa must be > 0");
  }
  if (!(valid_min_duty_pct < valid_max_duty_pct)) {
    throw std::invalid_argument("nozzle line fit: valid_min_duty_pct must be below valid_max");
  }
  NozzleLineFit fit;
  double sum_s = 0.0, sum_q = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const DutyFlowPoint& p = points[i];
    if (!std::isfinite(p.duty_pct) || !std::isfinite(p.flow_l_per_min)) {
      throw std::invalid_argument("nozzle line fit: point " + std::to_string(i) + " is not finite");
    }
    if (p.duty_pct < valid_min_duty_pct || p.duty_pct > valid_max_duty_pct) {
      ++fit.points_rejected;
      continue;
    }
    ++fit.points_used;
    sum_s += p.duty_pct;
    sum_q += p.flow_l_per_min;
  }
  if (fit.points_used < 2) {
    throw std::invalid_argument(
        "nozzle line fit: need >= 2 points inside the valid duty range, got " +
        std::to_string(fit.points_used));
  }
  const double n = static_cast<double>(fit.points_used);
  const double mean_s = sum_s / n;
  const double mean_q = sum_q / n;
  double sss = 0.0, ssq = 0.0, ssq_total = 0.0;
  for (const DutyFlowPoint& p : points) {
    if (p.duty_pct < valid_min_duty_pct || p.duty_pct > valid_max_duty_pct) continue;
    sss += (p.duty_pct - mean_s) * (p.duty_pct - mean_s);
    ssq += (p.duty_pct - mean_s) * (p.flow_l_per_min - mean_q);
    ssq_total += (p.flow_l_per_min - mean_q) * (p.flow_l_per_min - mean_q);
  }
  if (sss <= 0.0) {
    throw std::invalid_argument("nozzle line fit: all points in range have the same duty");
  }
  fit.line.slope_l_per_min_per_pct = ssq / sss;
  fit.line.intercept_l_per_min = mean_q - fit.line.slope_l_per_min_per_pct * mean_s;
  fit.line.calibration_pressure_mpa = pressure_mpa;
  double ss_residual = 0.0;
  for (const DutyFlowPoint& p : points) {
    if (p.duty_pct < valid_min_duty_pct || p.duty_pct > valid_max_duty_pct) continue;
    const double predicted =
        fit.line.slope_l_per_min_per_pct * p.duty_pct + fit.line.intercept_l_per_min;
    ss_residual += (p.flow_l_per_min - predicted) * (p.flow_l_per_min - predicted);
  }
  fit.r_squared = ssq_total > 0.0 ? 1.0 - ss_residual / ssq_total : 1.0;
  fit.residual_rms_l_per_min = std::sqrt(ss_residual / n);
  return fit;
}

}  // namespace weedspray::control
