// SPDX-License-Identifier: Apache-2.0
#include "control/turn_rate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <span>
#include <vector>

#include "control/nozzle_scheduler.hpp"

namespace weedspray::control {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(CourseDifference, WrapsAcrossNorth) {
  EXPECT_DOUBLE_EQ(course_difference_deg(350, 10), 20);
  EXPECT_DOUBLE_EQ(course_difference_deg(10, 350), -20);
  EXPECT_DOUBLE_EQ(course_difference_deg(90, 45), -45);
  EXPECT_DOUBLE_EQ(course_difference_deg(0, 180), 180);
}

// A right turn at 9 deg/s (2 m/s on a 12.7 m radius), fixes at 5 Hz, crossing north.
TEST(YawRateEstimator, FollowsASteadyTurnAcrossNorth) {
  YawRateEstimator yaw(YawRateConfig{});
  double course = 330;
  for (int i = 0; i < 30; ++i) {
    const double rate = yaw.add_fix(std::fmod(course, 360.0), 2.0, i * 0.2);
    if (i >= 15) {  // 3 s: six filter time constants
      EXPECT_NEAR(rate, 9.0, 0.03) << "fix " << i;
    }
    course += 9.0 * 0.2;
  }
  // Straight again: the rate decays to zero.
  for (int i = 30; i < 50; ++i) yaw.add_fix(std::fmod(course, 360.0), 2.0, i * 0.2);
  EXPECT_NEAR(yaw.rate_deg_per_s(), 0.0, 0.01);
}

TEST(YawRateEstimator, LeftTurnIsNegative) {
  YawRateEstimator yaw(
      YawRateConfig{.min_speed_m_per_s = 0.3, .filter_time_constant_s = 0, .max_fix_gap_s = 2.0});
  yaw.add_fix(20, 1.5, 0.0);
  EXPECT_DOUBLE_EQ(yaw.add_fix(10, 1.5, 0.5), -20.0);
}

TEST(YawRateEstimator, SlowOrMissingFixesGiveNoRate) {
  YawRateEstimator yaw(
      YawRateConfig{.min_speed_m_per_s = 0.3, .filter_time_constant_s = 0, .max_fix_gap_s = 2.0});
  yaw.add_fix(0, 2.0, 0.0);
  EXPECT_DOUBLE_EQ(yaw.add_fix(10, 2.0, 1.0), 10.0);
  // A standing receiver's course wanders: no rate, and no difference across the stop.
  EXPECT_DOUBLE_EQ(yaw.add_fix(200, 0.1, 2.0), 0.0);
  EXPECT_DOUBLE_EQ(yaw.add_fix(40, 2.0, 3.0), 0.0);
  EXPECT_DOUBLE_EQ(yaw.add_fix(50, 2.0, 4.0), 10.0);
  // A course not given breaks the chain; a gap longer than max_fix_gap_s makes no rate.
  EXPECT_DOUBLE_EQ(yaw.add_fix(NAN, 2.0, 5.0), 0.0);
  EXPECT_DOUBLE_EQ(yaw.add_fix(60, 2.0, 6.0), 0.0);
  EXPECT_DOUBLE_EQ(yaw.add_fix(90, 2.0, 9.0), 0.0);
  // The same fix again changes nothing.
  EXPECT_DOUBLE_EQ(yaw.add_fix(100, 2.0, 10.0), 10.0);
  EXPECT_DOUBLE_EQ(yaw.add_fix(100, 2.0, 10.0), 10.0);
}

// A rigid boom on a circle: each nozzle's speed is its radius times the turn's angular rate.
TEST(NozzleGroundSpeed, IsRadiusTimesAngularRate) {
  const double v = 2.0, radius = 12.0;
  const double rate_deg = v / radius * 180.0 / kPi;  // clockwise: a right turn
  for (double y : {-3.0, -0.75, 0.0, 0.75, 3.0}) {
    EXPECT_NEAR(nozzle_ground_speed_m_per_s(v, rate_deg, y), v * (radius - y) / radius, 1e-12);
    EXPECT_NEAR(nozzle_ground_speed_m_per_s(v, -rate_deg, y), v * (radius + y) / radius, 1e-12);
  }
  // Tighter than the nozzle's offset: it would move backwards; taken as standing.
  EXPECT_EQ(nozzle_ground_speed_m_per_s(v, rate_deg, 15.0), 0.0);
}

// World geometry on a right-hand curve: a weed imaged beside nozzle n's line, `ahead` metres
// ahead of the camera's nadir, comes under that nozzle after about ahead + camera_to_nozzle of
// the NOZZLE's own travel, which the per-nozzle plan uses; on the centre line's odometer the
// outer and inner nozzles would miss it by (1 - v_n / v) x that distance.
TEST(NozzleSchedulerOnACurve, PlanInEachNozzlesOdometerHitsTheWeed) {
  const double radius = 12.0, c2n = 1.2, ahead = 2.0;
  CameraGeometry g;
  g.mount_height_m = 1.0;
  g.tilt_from_vertical_rad = 0.5 * (std::atan(1.0) + std::atan(3.0));
  g.vertical_fov_rad = std::atan(3.0) - std::atan(1.0);
  g.camera_to_nozzle_m = c2n;
  NozzleSchedulerConfig config;
  config.geometry = g;
  config.nozzles = 2;  // nozzle 0: 1.5 m left (outer), nozzle 1: 1.5 m right (inner)
  config.rows = 1;
  config.opening_delay_s = 0;
  config.closing_delay_s = 0;
  const double offsets[2] = {-1.5, 1.5};
  const GroundInterval footprint = ground_footprint(g);
  ASSERT_LT(footprint.near_m, ahead);
  ASSERT_GT(footprint.far_m, ahead);

  for (int n = 0; n < 2; ++n) {
    const double y = offsets[n];
    // The true arc the nozzle runs until the weed at (y right, `ahead` forward of the nadir at
    // capture) is beside it: heading theta = s / R clockwise, centre of the turn at (R, 0).
    double nozzle_arc = -1;
    for (int i = 0; i < 100000; ++i) {
      const double s = i * 1e-4, th = s / radius;
      const double fx = std::sin(th), fy = std::cos(th), rx = std::cos(th), ry = -std::sin(th);
      const double nx = radius - radius * std::cos(th) - c2n * fx + y * rx;
      const double ny = radius * std::sin(th) - c2n * fy + y * ry;
      if ((y - nx) * fx + (ahead - ny) * fy <= 0) {
        nozzle_arc = s * (radius - y) / radius;
        break;
      }
    }
    ASSERT_GT(nozzle_arc, 0);
    // The plan: the frame pinned at each nozzle's odometer 0 (at capture), the one zone
    // sprayed; where along the nozzle's own travel does the sprayed ground cover the weed?
    NozzleScheduler scheduler(config);
    const double odometers[2] = {0.0, 0.0};
    const double duty[2] = {50.0, 50.0};
    ASSERT_TRUE(scheduler.add_frame(std::span<const double>(odometers, 2),
                                    std::span<const double>(duty, 2)));
    const double planned_arc = ahead + c2n;  // the weed's point in the nozzle's odometer
    EXPECT_GT(scheduler.duty_at(static_cast<std::size_t>(n), planned_arc, 1.0), 0.0);
    EXPECT_NEAR(planned_arc, nozzle_arc, 0.05) << "nozzle at " << y << " m";
    // The centre line's odometer reaches ahead + c2n when this nozzle has run k times that.
    const double k = (radius - y) / radius;
    EXPECT_GT(std::abs(k * planned_arc - nozzle_arc), 0.3) << "nozzle at " << y << " m";
  }
}

TEST(NozzleSchedulerOnACurve, PerNozzleOdometerFrameRejectsWrongSizes) {
  NozzleSchedulerConfig config;
  config.nozzles = 2;
  NozzleScheduler scheduler(config);
  const double one[1] = {0.0};
  const double two[2] = {0.0, 0.0};
  EXPECT_FALSE(scheduler.add_frame(std::span<const double>(one, 1), std::span<const double>(two)));
  EXPECT_FALSE(scheduler.add_frame(std::span<const double>(two, 2), std::span<const double>(one)));
}

}  // namespace
}  // namespace weedspray::control
