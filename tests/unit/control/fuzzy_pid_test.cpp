// SPDX-License-Identifier: Apache-2.0
#include "control/fuzzy_pid.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace weedspray::control {
namespace {

constexpr FuzzyInferenceConfig kCentroid{FuzzyDefuzzification::kSampledCentroid, 0.01};
constexpr FuzzyInferenceConfig kCentres{FuzzyDefuzzification::kTermCentres, 0.01};

TEST(FuzzyRules, TablesMatchTheSpecCorners) {
  using enum FuzzyTerm;
  EXPECT_EQ(kDeltaKpRules[0][0], PB);
  EXPECT_EQ(kDeltaKpRules[6][6], NB);
  EXPECT_EQ(kDeltaKpRules[3][3], ZO);
  EXPECT_EQ(kDeltaKpRules[1][6], NS);
  EXPECT_EQ(kDeltaKiRules[0][0], NB);
  EXPECT_EQ(kDeltaKiRules[4][6], PB);
  EXPECT_EQ(kDeltaKiRules[6][0], ZO);
  EXPECT_EQ(kDeltaKdRules[0][0], PS);
  EXPECT_EQ(kDeltaKdRules[0][6], PS);
  EXPECT_EQ(kDeltaKdRules[5][0], PB);
  EXPECT_EQ(kDeltaKdRules[6][1], PM);
  EXPECT_EQ(kDeltaKdRules[4][3], ZO);
}

TEST(FuzzyMembership, TrianglesWithShoulders) {
  EXPECT_DOUBLE_EQ(fuzzy_input_membership(FuzzyTerm::NB, -6.0), 1.0);
  EXPECT_DOUBLE_EQ(fuzzy_input_membership(FuzzyTerm::NB, -7.0), 1.0);
  EXPECT_DOUBLE_EQ(fuzzy_input_membership(FuzzyTerm::PB, 9.0), 1.0);
  EXPECT_DOUBLE_EQ(fuzzy_input_membership(FuzzyTerm::NB, -5.0), 0.5);
  EXPECT_DOUBLE_EQ(fuzzy_input_membership(FuzzyTerm::NM, -5.0), 0.5);
  EXPECT_DOUBLE_EQ(fuzzy_input_membership(FuzzyTerm::ZO, 0.5), 0.75);
  EXPECT_DOUBLE_EQ(fuzzy_input_membership(FuzzyTerm::PS, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(fuzzy_input_membership(FuzzyTerm::NB, 6.0), 0.0);
}

TEST(FuzzyQuantise, LinearAndClamped) {
  EXPECT_DOUBLE_EQ(fuzzy_quantise(0.1, 0.4), 1.5);
  EXPECT_DOUBLE_EQ(fuzzy_quantise(-0.1, 0.4), -1.5);
  EXPECT_DOUBLE_EQ(fuzzy_quantise(1.0, 0.4), 6.0);
  EXPECT_DOUBLE_EQ(fuzzy_quantise(-1.0, 0.4), -6.0);
  EXPECT_DOUBLE_EQ(fuzzy_quantise(1.0, 0.0), 0.0);
}

TEST(FuzzyInference, CornerNbNbWithTermCentres) {
  // e = NB, ec = NB at full membership fires one rule: dKp = PB, dKi = NB, dKd = PS.
  const FuzzyGainCorrection c = fuzzy_infer(-6.0, -6.0, kCentres);
  EXPECT_DOUBLE_EQ(c.d_kp, 6.0);
  EXPECT_DOUBLE_EQ(c.d_ki, -6.0);
  EXPECT_DOUBLE_EQ(c.d_kd, 2.0);
}

TEST(FuzzyInference, CornerNbNbWithSampledCentroid) {
  // PB alone is the half triangle on [4, 6] peaking at 6: centroid (4 + 6 + 6) / 3.
  const FuzzyGainCorrection c = fuzzy_infer(-6.0, -6.0, kCentroid);
  EXPECT_NEAR(c.d_kp, 16.0 / 3.0, 1e-3);
  EXPECT_NEAR(c.d_ki, -16.0 / 3.0, 1e-3);
  EXPECT_NEAR(c.d_kd, 2.0, 1e-9);  // PS is a whole triangle centred at 2
}

TEST(FuzzyInference, CornerPbPb) {
  const FuzzyGainCorrection c = fuzzy_infer(6.0, 6.0, kCentres);
  EXPECT_DOUBLE_EQ(c.d_kp, -6.0);  // NB
  EXPECT_DOUBLE_EQ(c.d_ki, 6.0);   // PB
  EXPECT_DOUBLE_EQ(c.d_kd, 6.0);   // PB
}

TEST(FuzzyInference, PointBetweenTwoErrorTerms) {
  // qe = -5: NB 0.5, NM 0.5; qec = 0: ZO 1. Rules fired at 0.5 each:
  //   dKp: (NB,ZO) = PM, (NM,ZO) = PS;  dKi: NM, NS;  dKd: NB, NM.
  const FuzzyGainCorrection centres = fuzzy_infer(-5.0, 0.0, kCentres);
  EXPECT_DOUBLE_EQ(centres.d_kp, 3.0);
  EXPECT_DOUBLE_EQ(centres.d_ki, -3.0);
  EXPECT_DOUBLE_EQ(centres.d_kd, -5.0);
  const FuzzyGainCorrection centroid = fuzzy_infer(-5.0, 0.0, kCentroid);
  EXPECT_NEAR(centroid.d_kp, 3.0, 1e-3);   // symmetric union of PS and PM clipped at 0.5
  EXPECT_NEAR(centroid.d_ki, -3.0, 1e-3);  // same for NM and NS
  // dKd: NB (half triangle) and NM clipped at 0.5: flat 0.5 on [-6, -3] (area 1.5, centre
  // -4.5) plus a falling ramp on [-3, -2] (area 0.25, centre -8/3).
  EXPECT_NEAR(centroid.d_kd, (1.5 * -4.5 + 0.25 * (-8.0 / 3.0)) / 1.75, 1e-3);
}

TEST(FuzzyInference, PointBetweenTwoErrorChangeTerms) {
  // qe = 0 (ZO), qec = -3: NM 0.5, NS 0.5. dKp row ZO: PM, PS -> 3. dKi: NM, NS -> -3.
  const FuzzyGainCorrection c = fuzzy_infer(0.0, -3.0, kCentres);
  EXPECT_DOUBLE_EQ(c.d_kp, 3.0);
  EXPECT_DOUBLE_EQ(c.d_ki, -3.0);
  EXPECT_DOUBLE_EQ(c.d_kd, -2.0);
}

TEST(FuzzyGainTable, ExactOnGridAndCloseBetween) {
  const FuzzyGainTable table(kCentroid, 10);
  for (double qe : {-6.0, -5.0, -2.3, 0.0, 1.7, 6.0}) {
    for (double qec : {-6.0, -0.4, 0.0, 3.1, 6.0}) {
      const FuzzyGainCorrection exact = fuzzy_infer(qe, qec, kCentroid);
      const FuzzyGainCorrection looked = table.lookup(qe, qec);
      EXPECT_NEAR(looked.d_kp, exact.d_kp, 1e-9) << qe << "," << qec;
      EXPECT_NEAR(looked.d_ki, exact.d_ki, 1e-9);
      EXPECT_NEAR(looked.d_kd, exact.d_kd, 1e-9);
    }
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> in(-6.0, 6.0);
  double worst = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const double qe = in(rng), qec = in(rng);
    const FuzzyGainCorrection exact = fuzzy_infer(qe, qec, kCentroid);
    const FuzzyGainCorrection looked = table.lookup(qe, qec);
    worst = std::max({worst, std::abs(looked.d_kp - exact.d_kp), std::abs(looked.d_ki - exact.d_ki),
                      std::abs(looked.d_kd - exact.d_kd)});
  }
  // Interpolation error on a 0.1 grid, in quantised units (the domain spans 12).
  EXPECT_LT(worst, 0.05);
  // Out-of-range inputs clamp to the edge.
  EXPECT_NEAR(table.lookup(-50.0, -50.0).d_kp, fuzzy_infer(-6.0, -6.0, kCentroid).d_kp, 1e-9);
}

TEST(FuzzyPid, GainsAreBasePlusWeightedCorrection) {
  FuzzyPidConfig config;
  config.base.gains = {1.0, 0.5, 0.05};
  config.correction_weights = {0.1, 0.02, 0.001};
  config.error_range = 0.4;
  config.inference = kCentres;
  FuzzyPid pid(config);
  pid.update(0.2, 0.0, 0.01);  // e = 0.2 -> qe = 3 (PS 0.5, PM 0.5); first cycle ec = 0
  const FuzzyGainCorrection expected = FuzzyGainTable(kCentres, 10).lookup(3.0, 0.0);
  EXPECT_NEAR(pid.last_correction().d_kp, expected.d_kp, 1e-12);
  EXPECT_NEAR(pid.current_gains().kp, 1.0 + expected.d_kp * 0.1, 1e-12);
  EXPECT_NEAR(pid.current_gains().ki, 0.5 + expected.d_ki * 0.02, 1e-12);
  EXPECT_NEAR(pid.current_gains().kd, 0.05 + expected.d_kd * 0.001, 1e-12);
  // Hand check: (PS,ZO) -> NS, (PM,ZO) -> NM at 0.5 each: dKp = -3.
  EXPECT_NEAR(expected.d_kp, -3.0, 1e-12);
}

TEST(FuzzyPid, ZeroWeightsBehaveLikeThePlainPid) {
  FuzzyPidConfig config;
  config.base.gains = {0.8, 2.0, 0.01};
  config.base.output_min = 0.0;
  config.base.output_max = 1.0;
  FuzzyPid fuzzy(config);
  Pid plain(config.base);
  double y = 0.0;
  for (int i = 0; i < 500; ++i) {
    const double u_fuzzy = fuzzy.update(0.2, y, 0.01);
    const double u_plain = plain.update(0.2, y, 0.01);
    ASSERT_DOUBLE_EQ(u_fuzzy, u_plain) << "cycle " << i;
    y += (0.4 * u_fuzzy - y) * 0.01 / 0.2;  // first-order plant, tau 0.2 s
  }
}

TEST(FuzzyPid, ErrorRateRangeDefaultsToTwiceTheRange) {
  FuzzyPidConfig config;
  config.base.gains = {1.0, 1.0, 0.0};
  config.correction_weights = {1.0, 1.0, 0.0};
  config.error_range = 0.5;
  config.inference = kCentres;
  FuzzyPid pid(config);
  pid.update(0.0, 0.0, 0.1);
  // The measurement rises 0.1 in 0.1 s: de/dt = -1 /s -> qec = 6 * -1 / 1.0 = -6 (NB); e = -0.1
  // -> qe = -1.2 (NS 0.6, ZO 0.4). dKp: (NS,NB) = PM, (ZO,NB) = PM -> 4.
  pid.update(0.0, 0.1, 0.1);
  EXPECT_NEAR(pid.last_correction().d_kp, 4.0, 1e-9);
}

TEST(FuzzyInference, ExactCentroidIsTheLimitOfTheSampledOne) {
  const FuzzyInferenceConfig exact{FuzzyDefuzzification::kExactCentroid, 0.01};
  const FuzzyInferenceConfig fine{FuzzyDefuzzification::kSampledCentroid, 0.001};
  for (double qe = -6.0; qe <= 6.0; qe += 0.7) {
    for (double qec = -6.0; qec <= 6.0; qec += 0.9) {
      const FuzzyGainCorrection a = fuzzy_infer(qe, qec, exact);
      const FuzzyGainCorrection b = fuzzy_infer(qe, qec, fine);
      EXPECT_NEAR(a.d_kp, b.d_kp, 1e-4) << qe << "," << qec;
      EXPECT_NEAR(a.d_ki, b.d_ki, 1e-4) << qe << "," << qec;
      EXPECT_NEAR(a.d_kd, b.d_kd, 1e-4) << qe << "," << qec;
    }
  }
  EXPECT_NEAR(fuzzy_infer(-6.0, -6.0, exact).d_kp, 16.0 / 3.0, 1e-12);
}

TEST(FuzzyPid, ControllersWithOtherGainsShareOneTable) {
  const FuzzyInferenceConfig inference{};
  const auto a = shared_fuzzy_gain_table(inference, 10);
  EXPECT_EQ(a.get(), shared_fuzzy_gain_table(inference, 10).get());
  EXPECT_NE(a.get(), shared_fuzzy_gain_table(inference, 5).get());

  FuzzyPidConfig config;
  config.base.gains = {1.0, 0.5, 0.05};
  config.correction_weights = {0.1, 0.02, 0.001};
  config.error_range = 1.0;
  FuzzyPid pid(config);
  pid.enable(0.0, 0.5, 0.0);
  pid.update(0.5, 0.0, 0.01);
  const FuzzyGainCorrection c = pid.last_correction();
  // The table does not depend on the gains: another controller with other gains and weights
  // gets the same correction for the same e and ec, weighted by its own.
  config.base.gains = {2.0, 0.1, 0.0};
  config.correction_weights = {0.3, 0.0, 0.0};
  FuzzyPid other(config);
  other.enable(0.0, 0.5, 0.0);
  other.update(0.5, 0.0, 0.01);
  EXPECT_NEAR(other.last_correction().d_kp, c.d_kp, 1e-12);
  EXPECT_NEAR(other.current_gains().kp, std::max(0.0, 2.0 + c.d_kp * 0.3), 1e-12);
  EXPECT_NEAR(other.current_gains().ki, 0.1, 1e-12);
}

TEST(FuzzyPid, RejectsBadConfig) {
  FuzzyPidConfig config;
  config.error_range = 0.0;
  EXPECT_THROW(FuzzyPid{config}, std::invalid_argument);
  config = FuzzyPidConfig{};
  config.table_steps_per_unit = 0;
  EXPECT_THROW(FuzzyPid{config}, std::invalid_argument);
}

}  // namespace
}  // namespace weedspray::control
