// SPDX-License-Identifier: Apache-2.0
#include "control/spray_rate_law.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace weedspray::control {
namespace {

TEST(SprayRateLaw, NominalDoseOfTheWheatPaper) {
  EXPECT_NEAR(nominal_dose_l_per_m2(SprayLawConfig{}), 0.0205, 1e-12);
}

TEST(SprayRateLaw, TargetFlowAndDutyMatchTheClosedForm) {
  const SprayLawConfig config{};
  const NozzleLine line{};
  EXPECT_NEAR(target_flow_l_per_min(config, 0.5, 1.0), 0.3075, 1e-12);
  for (double k : {1.0, 0.8}) {
    SprayLawConfig c = config;
    c.max_density = k;
    for (double density : {0.4, 0.55, 0.75}) {
      for (double speed : {0.8, 1.0, 1.3}) {
        const double u = 0.0205;
        // s = (60 D w v u - b k) / (A k)  (SPEC §2)
        const double closed_form = (60.0 * density * 0.5 * speed * u - 0.217 * k) / (0.00393 * k);
        const SprayDecision d = spray_decision(c, line, density, speed, 0.4);
        EXPECT_NEAR(d.raw_duty_pct, closed_form, 1e-9) << k << " " << density << " " << speed;
      }
    }
  }
}

TEST(SprayRateLaw, ClampsOutsideTheValidRange) {
  SprayLawConfig config{};
  const NozzleLine line{};
  // D = 0.4 at 1 m/s: q = 0.246, s = 7.4 % -> closed.
  EXPECT_DOUBLE_EQ(spray_decision(config, line, 0.4, 1.0, 0.4).duty_pct, 0.0);
  // D = 0.5, 1.5 m/s: q = 0.461, s = 62 % -> kept.
  const SprayDecision mid = spray_decision(config, line, 0.5, 1.5, 0.4);
  EXPECT_NEAR(mid.duty_pct, (0.46125 - 0.217) / 0.00393, 1e-9);
  // D = 1, 2 m/s: s = 101 % -> fully open.
  EXPECT_DOUBLE_EQ(spray_decision(config, line, 1.0, 2.0, 0.4).duty_pct, 100.0);
  config.min_duty_pct = 5.0;  // the limits are config
  EXPECT_GT(spray_decision(config, line, 0.4, 1.0, 0.4).duty_pct, 5.0);
  config.max_duty_pct = 50.0;
  EXPECT_DOUBLE_EQ(clamp_duty_pct(config, 60.0), 100.0);
}

TEST(SprayRateLaw, DecisionThresholdAndStandstillSprayNothing) {
  SprayLawConfig config{};
  config.decision_threshold = 0.05;
  EXPECT_DOUBLE_EQ(target_flow_l_per_min(config, 0.049, 1.0), 0.0);
  EXPECT_GT(target_flow_l_per_min(config, 0.051, 1.0), 0.0);
  EXPECT_DOUBLE_EQ(target_flow_l_per_min(config, 0.5, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(spray_decision(config, NozzleLine{}, 0.5, 0.0, 0.4).duty_pct, 0.0);
}

TEST(SprayRateLaw, PressureCompensationFollowsSqrtLaw) {
  const NozzleLine through_origin{0.01, 0.0, 0.4, 0.0};
  // b = 0: duty scales exactly by sqrt(P_cal / P).
  const double at_cal = raw_duty_for_flow_pct(through_origin, 0.5, 0.4);
  EXPECT_NEAR(raw_duty_for_flow_pct(through_origin, 0.5, 0.3), at_cal * std::sqrt(0.4 / 0.3),
              1e-12);
  // With an intercept the inverse is exact: flow(duty(q, P), P) == q.
  const NozzleLine line{};
  for (double p : {0.2, 0.3, 0.4, 0.5}) {
    const double duty = raw_duty_for_flow_pct(line, 0.35, p);
    EXPECT_NEAR(flow_for_duty_l_per_min(line, duty, p), 0.35, 1e-12) << p;
  }
  // Unusable pressure: no compensation.
  EXPECT_DOUBLE_EQ(raw_duty_for_flow_pct(line, 0.45, 0.0), raw_duty_for_flow_pct(line, 0.45, 0.4));
}

TEST(SprayRateLaw, RequestAtFullOpenFlowHoldsTheValveOpen) {
  NozzleLine line;  // A = 0.00393, b = 0.217 at 0.4 MPa: the line gives 0.61 at 100 %
  line.full_open_flow_l_per_min = 0.58;
  EXPECT_DOUBLE_EQ(raw_duty_for_flow_pct(line, 0.58, 0.4), 100.0);
  EXPECT_DOUBLE_EQ(raw_duty_for_flow_pct(line, 0.70, 0.4), 100.0);
  // Below it the line rules; at another pressure the full-open flow scales with sqrt(P).
  EXPECT_NEAR(raw_duty_for_flow_pct(line, 0.57, 0.4), (0.57 - 0.217) / 0.00393, 1e-9);
  EXPECT_DOUBLE_EQ(raw_duty_for_flow_pct(line, 0.58 * std::sqrt(0.5), 0.2), 100.0);
  EXPECT_LT(raw_duty_for_flow_pct(line, 0.57 * std::sqrt(0.5), 0.2), 100.0);
  // Above the calibration pressure the calibrated full flow itself still holds the valve open.
  EXPECT_DOUBLE_EQ(raw_duty_for_flow_pct(line, 0.58, 0.41), 100.0);
  // Unknown (0): no rule.
  line.full_open_flow_l_per_min = 0.0;
  EXPECT_GT(raw_duty_for_flow_pct(line, 0.70, 0.4), 100.0);
  line.full_open_flow_l_per_min = -1.0;
  EXPECT_THROW(validate(line), std::invalid_argument);
}

TEST(SprayRateLaw, LowDutyPolicyRaisesWeedyZonesToTheMinimumDose) {
  SprayLawConfig config;
  config.max_density = 0.75;
  config.decision_threshold = 0.05;
  const NozzleLine line;
  // Density 0.1: q = 0.082 L/min, below the intercept: raw duty negative.
  const SprayDecision closed = spray_decision(config, line, 0.1, 1.0, 0.4);
  EXPECT_LT(closed.raw_duty_pct, 0.0);
  EXPECT_DOUBLE_EQ(closed.duty_pct, 0.0);
  config.low_duty_policy = LowDutyPolicy::kRaiseToMin;
  EXPECT_DOUBLE_EQ(spray_decision(config, line, 0.1, 1.0, 0.4).duty_pct, 20.0);
  // Below the decision threshold nothing is sprayed under either policy.
  EXPECT_DOUBLE_EQ(spray_decision(config, line, 0.04, 1.0, 0.4).duty_pct, 0.0);
  // In the valid band and above it the policies agree.
  const SprayDecision mid = spray_decision(config, line, 0.6, 1.0, 0.4);
  EXPECT_NEAR(mid.duty_pct, mid.raw_duty_pct, 1e-12);
  EXPECT_DOUBLE_EQ(clamp_duty_for_flow_pct(config, 90.0, 0.6), 100.0);
  EXPECT_DOUBLE_EQ(clamp_duty_for_flow_pct(config, 10.0, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(clamp_duty_for_flow_pct(config, std::nan(""), 0.3), 20.0);
  // clamp_duty_pct keeps the SPEC clamp whatever the policy (it does not know the flow).
  EXPECT_DOUBLE_EQ(clamp_duty_pct(config, 10.0), 0.0);
}

TEST(SprayRateLaw, ApplicationRate) {
  EXPECT_NEAR(application_rate_l_per_ha(1.0, 1.0, 0.5), 10000.0 / 30.0, 1e-9);
  EXPECT_DOUBLE_EQ(application_rate_l_per_ha(1.0, 0.0, 0.5), 0.0);
}

TEST(DutyQuantiser, HysteresisStopsChatter) {
  const std::vector<double> levels{0, 20, 40, 60, 80, 100};
  DutyQuantiser q(levels, 3.0);
  EXPECT_DOUBLE_EQ(q.quantise(29.0), 20.0);
  EXPECT_DOUBLE_EQ(q.quantise(31.0), 20.0);  // band of 20 reaches 30 + 3
  EXPECT_DOUBLE_EQ(q.quantise(29.0), 20.0);
  EXPECT_DOUBLE_EQ(q.quantise(34.0), 40.0);
  EXPECT_DOUBLE_EQ(q.quantise(28.0), 40.0);  // band of 40 reaches down to 27
  EXPECT_DOUBLE_EQ(q.quantise(26.0), 20.0);
  EXPECT_DOUBLE_EQ(q.quantise(95.0), 100.0);
  EXPECT_DOUBLE_EQ(q.quantise(-5.0), 0.0);
  // Without hysteresis the same alternating input flips every frame.
  DutyQuantiser plain(levels, 0.0);
  EXPECT_DOUBLE_EQ(plain.quantise(29.0), 20.0);
  EXPECT_DOUBLE_EQ(plain.quantise(31.0), 40.0);
}

TEST(DutyQuantiser, CustomLevelsAndValidation) {
  const std::vector<double> levels{0, 25, 50, 100};
  DutyQuantiser q(levels, 0.0);
  EXPECT_DOUBLE_EQ(q.quantise(70.0), 50.0);
  EXPECT_DOUBLE_EQ(q.quantise(80.0), 100.0);
  const std::vector<double> descending{50, 25};
  EXPECT_THROW(DutyQuantiser(descending, 1.0), std::invalid_argument);
  EXPECT_THROW(DutyQuantiser(levels, -1.0), std::invalid_argument);
  EXPECT_THROW(DutyQuantiser(std::vector<double>{}, 0.0), std::invalid_argument);
}

TEST(SprayRateLaw, ValidationNamesTheField) {
  SprayLawConfig config{};
  config.nozzle_width_m = 0.0;
  try {
    validate(config);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nozzle_width_m"), std::string::npos);
  }
  config = SprayLawConfig{};
  config.min_duty_pct = 90.0;
  EXPECT_THROW(validate(config), std::invalid_argument);
  NozzleLine line{};
  line.slope_l_per_min_per_pct = 0.0;
  EXPECT_THROW(validate(line), std::invalid_argument);
  EXPECT_NO_THROW(validate(SprayLawConfig{}));
}

}  // namespace
}  // namespace weedspray::control
