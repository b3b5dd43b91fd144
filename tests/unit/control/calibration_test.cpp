// SPDX-License-Identifier: Apache-2.0
#include "control/calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace weedspray::control {
namespace {

TEST(FlowMeterCalibration, PulsesPerLitreAndConfigError) {
  FlowMeterCalibration c = calibrate_flow_meter(8925, 1.05, 8500.0);
  EXPECT_NEAR(c.pulses_per_litre, 8500.0, 1e-9);
  EXPECT_NEAR(c.error_pct, 0.0, 1e-9);
  c = calibrate_flow_meter(9350, 1.0, 8500.0);
  EXPECT_NEAR(c.pulses_per_litre, 9350.0, 1e-9);
  EXPECT_NEAR(c.error_pct, (8500.0 - 9350.0) / 9350.0 * 100.0, 1e-9);
  EXPECT_DOUBLE_EQ(c.configured_pulses_per_litre, 8500.0);
}

TEST(FlowMeterCalibration, RejectsBadInput) {
  EXPECT_THROW(calibrate_flow_meter(0, 1.0, 8500.0), std::invalid_argument);
  EXPECT_THROW(calibrate_flow_meter(100, 0.0, 8500.0), std::invalid_argument);
  EXPECT_THROW(calibrate_flow_meter(100, 1.0, -1.0), std::invalid_argument);
}

TEST(NozzleLineFit, RecoversAnExactLineAndRejectsOutOfRange) {
  std::vector<DutyFlowPoint> points;
  for (double s : {10.0, 20.0, 35.0, 50.0, 65.0, 80.0, 95.0}) {
    points.push_back({s, 0.00393 * s + 0.217});
  }
  const NozzleLineFit fit = fit_nozzle_line(points, 0.4);
  EXPECT_NEAR(fit.line.slope_l_per_min_per_pct, 0.00393, 1e-12);
  EXPECT_NEAR(fit.line.intercept_l_per_min, 0.217, 1e-12);
  EXPECT_DOUBLE_EQ(fit.line.calibration_pressure_mpa, 0.4);
  EXPECT_NEAR(fit.r_squared, 1.0, 1e-12);
  EXPECT_EQ(fit.points_used, 5u);
  EXPECT_EQ(fit.points_rejected, 2u);
}

TEST(NozzleLineFit, HandComputedNoisyFit) {
  const std::vector<DutyFlowPoint> points{{20, 0.30}, {40, 0.37}, {60, 0.46}, {80, 0.53}};
  const NozzleLineFit fit = fit_nozzle_line(points, 0.4);
  // Sxx = 2000, Sxy = 7.8 -> A = 0.0039, b = 0.415 - 0.0039 * 50 = 0.22.
  EXPECT_NEAR(fit.line.slope_l_per_min_per_pct, 0.0039, 1e-12);
  EXPECT_NEAR(fit.line.intercept_l_per_min, 0.22, 1e-12);
  // Residuals 0.002 -0.006 0.006 -0.002: SSres = 8e-5, SStot = 0.0305.
  EXPECT_NEAR(fit.r_squared, 1.0 - 8e-5 / 0.0305, 1e-9);
  EXPECT_NEAR(fit.residual_rms_l_per_min, std::sqrt(8e-5 / 4.0), 1e-12);
}

TEST(NozzleLineFit, NeedsTwoDistinctDutiesInRange) {
  const std::vector<DutyFlowPoint> one_in_range{{10, 0.2}, {50, 0.4}, {90, 0.6}};
  EXPECT_THROW(fit_nozzle_line(one_in_range, 0.4), std::invalid_argument);
  const std::vector<DutyFlowPoint> same_duty{{50, 0.4}, {50, 0.41}};
  EXPECT_THROW(fit_nozzle_line(same_duty, 0.4), std::invalid_argument);
  const std::vector<DutyFlowPoint> fine{{30, 0.3}, {60, 0.4}};
  EXPECT_THROW(fit_nozzle_line(fine, 0.0), std::invalid_argument);
  // A wider validity range accepts the end points.
  EXPECT_EQ(fit_nozzle_line(one_in_range, 0.4, 0.0, 100.0).points_used, 3u);
}

}  // namespace
}  // namespace weedspray::control
