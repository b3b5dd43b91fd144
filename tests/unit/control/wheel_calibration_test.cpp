// SPDX-License-Identifier: Apache-2.0
#include "control/wheel_calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

namespace weedspray::control {
namespace {

constexpr double kLat0 = 52.0, kLon0 = 5.0;

// Metres north/east of the start -> a fix (small-area inverse of ground_distance_m's radii).
CalibrationFix fix_at(double north_m, double east_m, double course_deg, double speed = 2.0) {
  constexpr double kA = 6378137.0, kE2 = 6.69437999014e-3, kRad = M_PI / 180.0;
  const double w = 1.0 - kE2 * std::pow(std::sin(kLat0 * kRad), 2);
  const double meridian = kA * (1.0 - kE2) / (w * std::sqrt(w));
  const double prime = kA / std::sqrt(w);
  CalibrationFix f;
  f.usable = true;
  f.latitude_deg = kLat0 + north_m / meridian / kRad;
  f.longitude_deg = kLon0 + east_m / (prime * std::cos(kLat0 * kRad)) / kRad;
  f.course_deg = course_deg;
  f.speed_m_per_s = speed;
  return f;
}

TEST(GroundDistance, MatchesTheEllipsoidAlongAMeridianAndAParallel) {
  // A degree of latitude at 52 deg N is 111 264 m on WGS84 and a degree of longitude 68 678 m
  // (the tabulated lengths of a degree); a 6371 km sphere gives 111 195 m for both meridian
  // degrees everywhere, 0.06 % short here and 0.5 % off near the poles or the equator.
  EXPECT_NEAR(ground_distance_m(52.0, 5.0, 52.01, 5.0), 1112.64, 0.05);
  EXPECT_NEAR(ground_distance_m(52.0, 5.0, 52.0, 5.01), 686.78, 0.05);
  // On the equator a degree of latitude is 110 574 m, at the pole 111 694 m.
  EXPECT_NEAR(ground_distance_m(-0.005, 0.0, 0.005, 0.0), 1105.74, 0.05);
  EXPECT_NEAR(ground_distance_m(89.985, 0.0, 89.995, 0.0), 1116.94, 0.05);
}

// Straight 120 m east at 2 m/s, 5 Hz fixes with 1.5 cm noise (RTK float), a wheel of
// 103.7 pulses per metre (a ground wheel on soft soil): calibrated within 0.1 %.
TEST(WheelCalibration, StraightRunGivesThePulsesPerMetre) {
  WheelCalibrationConfig config;
  config.run_distance_m = 100.0;
  WheelCalibration cal(config);
  cal.start();
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.015);
  const double true_ppm = 103.7;
  const std::uint64_t count0 = 5'000'000;
  WheelCalibrationStatus status;
  for (int k = 0; k <= 300 && status.state != WheelCalibrationState::kDone; ++k) {
    const double east = 0.4 * k;
    status = cal.add_fix(fix_at(noise(rng), east + noise(rng), 90.0 + noise(rng) * 10),
                         count0 + static_cast<std::uint64_t>(std::floor(east * true_ppm)));
  }
  ASSERT_EQ(status.state, WheelCalibrationState::kDone);
  EXPECT_GE(status.distance_m, 100.0);
  EXPECT_LT(status.distance_m, 101.0);
  EXPECT_NEAR(status.pulses_per_metre, true_ppm, true_ppm * 1e-3);
  EXPECT_EQ(status.restarts, 0u);
}

// A turn (or a stop) in the middle starts the run again: the result is the straight part's.
TEST(WheelCalibration, TurnOrStopRestartsTheRun) {
  WheelCalibrationConfig config;
  config.run_distance_m = 20.0;
  WheelCalibration cal(config);
  cal.start();
  const double ppm = 50.0;
  std::uint64_t count = 0;
  double north = 0, east = 0;
  // 10 m north, then a 30-degree bend: a chord through the bend would not be the path.
  for (int k = 0; k < 25; ++k) {
    north += 0.4;
    count += 20;
    EXPECT_NE(cal.add_fix(fix_at(north, east, 0.0), count).state, WheelCalibrationState::kDone);
  }
  const std::uint32_t restarts_before = cal.status().restarts;
  north += 0.35;
  east += 0.2;
  count += 20;
  cal.add_fix(fix_at(north, east, 30.0), count);
  EXPECT_EQ(cal.status().restarts, restarts_before + 1);
  EXPECT_EQ(cal.status().distance_m, 0.0);
  // A stop (too slow for a course): waits for the next run.
  cal.add_fix(fix_at(north, east, 30.0, 0.1), count);
  EXPECT_EQ(cal.status().state, WheelCalibrationState::kWaitingForRun);
  const double s = std::sin(M_PI / 6), c = std::cos(M_PI / 6);
  WheelCalibrationStatus status = cal.status();
  for (int k = 0; k < 80 && status.state != WheelCalibrationState::kDone; ++k) {
    north += 0.4 * c;
    east += 0.4 * s;
    count += 20;
    status = cal.add_fix(fix_at(north, east, 30.0), count);
  }
  ASSERT_EQ(status.state, WheelCalibrationState::kDone);
  EXPECT_NEAR(status.pulses_per_metre, ppm, ppm * 0.03);  // 20 pulses a 0.4 m step after the first
}

TEST(WheelCalibration, IdleUntilStartedAndKeepsItsResult) {
  WheelCalibration cal(WheelCalibrationConfig{.run_distance_m = 1.0});
  EXPECT_EQ(cal.add_fix(fix_at(0, 0, 0), 0).state, WheelCalibrationState::kIdle);
  cal.start();
  cal.add_fix(fix_at(0, 0, 0), 0);
  cal.add_fix(fix_at(1.0, 0, 0), 100);
  ASSERT_EQ(cal.status().state, WheelCalibrationState::kDone);
  EXPECT_NEAR(cal.status().pulses_per_metre, 100.0, 0.01);
  cal.add_fix(fix_at(2.0, 0, 0), 150);  // done: later fixes change nothing
  EXPECT_NEAR(cal.status().pulses_per_metre, 100.0, 0.01);
  // An unusable fix while running waits for a new run.
  cal.start();
  cal.add_fix(fix_at(0, 0, 0), 0);
  CalibrationFix lost = fix_at(0.5, 0, 0);
  lost.usable = false;
  EXPECT_EQ(cal.add_fix(lost, 50).state, WheelCalibrationState::kWaitingForRun);
}

TEST(WheelCalibration, WrappedCounterStillSubtracts) {
  WheelCalibration cal(WheelCalibrationConfig{.run_distance_m = 1.0});
  cal.start();
  const std::uint64_t near_wrap = ~std::uint64_t{0} - 40;
  cal.add_fix(fix_at(0, 0, 0), near_wrap);
  cal.add_fix(fix_at(1.0, 0, 0), near_wrap + 100);  // wraps past zero
  EXPECT_NEAR(cal.status().pulses_per_metre, 100.0, 0.01);
}

}  // namespace
}  // namespace weedspray::control
