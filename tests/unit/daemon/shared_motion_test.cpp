// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/shared_motion.hpp"

#include <gtest/gtest.h>

#include "daemon/sprayer/ground_speed.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

constexpr std::uint64_t kSenderEpochNs = 5'000'000'000'000;  // the owner's clock: its own epoch

SharedMotionSample motion_sample(double speed, double distance, std::chrono::nanoseconds sent,
                                 std::chrono::nanoseconds arrival, std::uint64_t count) {
  return {speed,   distance, kSenderEpochNs + static_cast<std::uint64_t>(sent.count()),
          arrival, count,    {}};
}

TEST(SharedMotion, NothingBeforeTheFirstSampleAndNoLossEither) {
  SharedMotionTracker tracker(500ms);
  tracker.update({}, 10s);
  EXPECT_FALSE(tracker.fresh());
  EXPECT_FALSE(tracker.had_sample());
  EXPECT_EQ(tracker.speed_m_per_s(), 0.0);
}

TEST(SharedMotion, TheOwnersOdometerRunsOnBetweenSamples) {
  SharedMotionTracker tracker(500ms);
  tracker.update(motion_sample(2.0, 100.0, 0ms, 1000ms + 10ms, 1), 1010ms);
  EXPECT_TRUE(tracker.fresh());
  EXPECT_DOUBLE_EQ(tracker.distance_m(), 100.0);
  tracker.update(motion_sample(2.0, 100.0, 0ms, 1010ms, 1), 1030ms);
  EXPECT_NEAR(tracker.distance_m(), 100.04, 1e-9);
  EXPECT_DOUBLE_EQ(tracker.speed_m_per_s(), 2.0);
}

// Samples every 50 ms, each delayed 5 ms or 40 ms: the odometer follows the owner's true
// odometer less its shortest transit, not the jitter.
TEST(SharedMotion, ALateSampleIsCarriedForwardByItsExtraAge) {
  SharedMotionTracker tracker(500ms);
  const double speed = 2.5;
  double worst_m = 0;
  for (std::uint64_t k = 1; k <= 40; ++k) {
    const auto sent = std::chrono::milliseconds(50 * k);
    const auto transit = k % 2 == 0 ? 40ms : 5ms;
    const double distance = speed * std::chrono::duration<double>(sent).count();
    const auto arrival = 1000s + sent + transit;
    tracker.update(motion_sample(speed, distance, sent, arrival, k), arrival);
    // The truth at arrival, less the shortest transit (5 ms), which no clock can see.
    const double truth = speed * std::chrono::duration<double>(sent + transit - 5ms).count();
    if (k > 2) worst_m = std::max(worst_m, std::abs(tracker.distance_m() - truth));
  }
  EXPECT_LT(worst_m, 0.002) << "the late samples' 35 ms of extra age was not carried";
  EXPECT_NEAR(tracker.extra_age_s(), 0.035, 0.002);
}

TEST(SharedMotion, SilenceForTheTimeoutIsALossThatHoldsTheOdometer) {
  SharedMotionTracker tracker(500ms);
  tracker.update(motion_sample(1.0, 10.0, 0ms, 1s, 1), 1s);
  tracker.update(motion_sample(1.0, 10.0, 0ms, 1s, 1), 1s + 500ms);
  EXPECT_TRUE(tracker.fresh());
  const double held = tracker.distance_m();
  tracker.update(motion_sample(1.0, 10.0, 0ms, 1s, 1), 1s + 501ms);
  EXPECT_FALSE(tracker.fresh());
  EXPECT_TRUE(tracker.had_sample());
  EXPECT_EQ(tracker.speed_m_per_s(), 0.0);
  tracker.update(motion_sample(1.0, 10.0, 0ms, 1s, 1), 5s);
  EXPECT_DOUBLE_EQ(tracker.distance_m(), held);
}

TEST(SharedMotion, AfterALossAnyNewSampleIsTakenEvenFromARestartedOwner) {
  SharedMotionTracker tracker(500ms);
  tracker.update(motion_sample(1.0, 50.0, 10s, 2s, 1), 2s);
  tracker.update(motion_sample(1.0, 50.0, 10s, 2s, 1), 3s);
  ASSERT_FALSE(tracker.fresh());
  // The owner restarted: its clock and odometer begin again.
  tracker.update(motion_sample(0.5, 0.0, 1s, 3s, 2), 3s);
  EXPECT_TRUE(tracker.fresh());
  EXPECT_DOUBLE_EQ(tracker.distance_m(), 0.0);
  EXPECT_DOUBLE_EQ(tracker.speed_m_per_s(), 0.5);
}

TEST(SharedMotion, AnOvertakenSampleIsIgnored) {
  SharedMotionTracker tracker(500ms);
  tracker.update(motion_sample(2.0, 10.0, 100ms, 1s, 1), 1s);
  tracker.update(motion_sample(9.0, 9.0, 50ms, 1s + 10ms, 2), 1s + 10ms);
  EXPECT_DOUBLE_EQ(tracker.speed_m_per_s(), 2.0);
  EXPECT_NEAR(tracker.distance_m(), 10.02, 1e-9);
}

TEST(SharedMotion, TheFleetSourceHasNoFallback) {
  GroundSpeedInputs in;
  in.source = SpeedSource::kFleet;
  in.wheel_wired = true;
  in.wheel_speed_m_per_s = 3;
  in.fixed_speed_m_per_s = 1;
  in.shared_fresh = true;
  in.shared_speed_m_per_s = 2;
  GroundSpeed speed = select_ground_speed(in);
  EXPECT_EQ(speed.speed_m_per_s, 2.0);
  EXPECT_EQ(speed.used, SpeedSource::kFleet);
  EXPECT_FALSE(speed.fell_back);
  in.shared_fresh = false;
  speed = select_ground_speed(in);
  EXPECT_EQ(speed.speed_m_per_s, 0.0);
  EXPECT_EQ(speed.used, SpeedSource::kFleet);
  EXPECT_TRUE(speed.fell_back);
  EXPECT_EQ(parse_speed_source("fleet"), SpeedSource::kFleet);
  EXPECT_EQ(to_string(SpeedSource::kFleet), "fleet");
}

}  // namespace
}  // namespace weedspray::daemon
