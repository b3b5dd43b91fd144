// SPDX-License-Identifier: Apache-2.0
#include "control/pid.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace weedspray::control {
namespace {

PidConfig config_with(PidGains gains, double lo = -10.0, double hi = 10.0) {
  PidConfig config;
  config.gains = gains;
  config.output_min = lo;
  config.output_max = hi;
  return config;
}

TEST(Pid, ProportionalOnlyIsGainTimesErrorClamped) {
  Pid pid(config_with({2.0, 0.0, 0.0}, -1.0, 1.0));
  EXPECT_DOUBLE_EQ(pid.update(0.3, 0.1, 0.01), 0.4);
  EXPECT_DOUBLE_EQ(pid.update(1.0, 0.0, 0.01), 1.0);
  EXPECT_DOUBLE_EQ(pid.update(-1.0, 0.0, 0.01), -1.0);
}

TEST(Pid, IntegralAccumulatesKiErrorDt) {
  Pid pid(config_with({0.0, 2.0, 0.0}));
  double out = 0.0;
  for (int i = 0; i < 10; ++i) out = pid.update(0.5, 0.4, 0.1);
  EXPECT_NEAR(out, 2.0 * 0.1 * 0.1 * 10, 1e-12);
  EXPECT_NEAR(pid.last_terms().integral, 0.2, 1e-12);
}

TEST(Pid, DerivativeActsOnMeasurementNotSetpoint) {
  Pid pid(config_with({0.0, 0.0, 1.0}));
  pid.update(0.0, 0.0, 0.1);
  // A set-point step gives no derivative kick.
  EXPECT_DOUBLE_EQ(pid.update(5.0, 0.0, 0.1), 0.0);
  // A rising measurement gives -kd * dy/dt.
  EXPECT_NEAR(pid.update(5.0, 0.2, 0.1), -2.0, 1e-12);
}

TEST(Pid, DerivativeFilterSmoothsAStep) {
  PidConfig config = config_with({0.0, 0.0, 1.0});
  config.derivative_filter_s = 0.1;
  Pid pid(config);
  pid.update(0.0, 0.0, 0.1);
  // Raw derivative -1; first-order filter with alpha = 0.1 / 0.2 = 0.5.
  EXPECT_NEAR(pid.update(0.0, 0.1, 0.1), -0.5, 1e-12);
}

TEST(Pid, ClampingAntiWindupStopsIntegratorAtSaturation) {
  Pid pid(config_with({0.0, 1.0, 0.0}, 0.0, 1.0));
  for (int i = 0; i < 1000; ++i) pid.update(1.0, 0.0, 0.1);  // would integrate to 100
  EXPECT_DOUBLE_EQ(pid.output(), 1.0);
  EXPECT_LE(pid.last_terms().integral, 1.0 + 1e-12);
  // The first cycle with a negative error leaves saturation.
  EXPECT_LT(pid.update(0.0, 0.5, 0.1), 1.0);
}

TEST(Pid, BackCalculationHoldsIntegratorNearTheLimit) {
  PidConfig config = config_with({0.0, 1.0, 0.0}, 0.0, 1.0);
  config.anti_windup = AntiWindup::kBackCalculation;
  config.tracking_gain_per_s = 10.0;
  Pid pid(config);
  for (int i = 0; i < 10000; ++i) pid.update(1.0, 0.0, 0.01);
  // Steady state of I' = I + ki e dt + kt (max - (I + ki e dt)) dt = I:
  // I = max + ki e / kt - ki e dt = 1 + 0.1 - 0.01.
  EXPECT_NEAR(pid.last_terms().integral, 1.09, 1e-9);
  double out = 1.0;
  for (int i = 0; i < 30 && out >= 1.0; ++i) out = pid.update(0.0, 1.0, 0.01);
  EXPECT_LT(out, 1.0);  // without anti-windup it would take ~100 s to unwind
}

TEST(Pid, BumplessEnableStartsFromTheCurrentOutput) {
  Pid pid(config_with({3.0, 0.5, 0.2}, 0.0, 1.0));
  pid.disable();
  EXPECT_FALSE(pid.enabled());
  pid.enable(0.6, 0.4, 0.35);
  const double first = pid.update(0.4, 0.35, 0.01);
  // Only the integral step of this cycle moves it: ki e dt.
  EXPECT_NEAR(first, 0.6 + 0.5 * 0.05 * 0.01, 1e-12);
}

TEST(Pid, GainChangeKeepsTheIntegralContribution) {
  Pid pid(config_with({0.0, 1.0, 0.0}));
  for (int i = 0; i < 10; ++i) pid.update(1.0, 0.0, 0.1);
  const double before = pid.update(0.0, 0.0, 0.1);  // zero error: output = integral
  pid.set_gains({0.0, 5.0, 0.0});
  EXPECT_DOUBLE_EQ(pid.update(0.0, 0.0, 0.1), before);
}

TEST(Pid, DisabledHoldsOutputAndResetClears) {
  Pid pid(config_with({1.0, 1.0, 0.0}));
  const double out = pid.update(1.0, 0.0, 0.1);
  pid.disable();
  EXPECT_DOUBLE_EQ(pid.update(5.0, 0.0, 0.1), out);
  pid.reset();
  EXPECT_DOUBLE_EQ(pid.output(), 0.0);
  EXPECT_DOUBLE_EQ(pid.last_terms().integral, 0.0);
}

TEST(Pid, BadTimeStepOrNanKeepsOutput) {
  Pid pid(config_with({1.0, 0.0, 0.0}));
  const double out = pid.update(1.0, 0.5, 0.1);
  EXPECT_DOUBLE_EQ(pid.update(1.0, 0.0, 0.0), out);
  EXPECT_DOUBLE_EQ(pid.update(1.0, std::numeric_limits<double>::quiet_NaN(), 0.1), out);
}

TEST(Pid, RejectsBadConfigNamingTheField) {
  PidConfig config;
  config.output_min = 1.0;
  config.output_max = 0.0;
  try {
    Pid pid(config);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("output_min"), std::string::npos);
  }
  config = PidConfig{};
  config.derivative_filter_s = -1.0;
  EXPECT_THROW(Pid{config}, std::invalid_argument);
}

}  // namespace
}  // namespace weedspray::control
