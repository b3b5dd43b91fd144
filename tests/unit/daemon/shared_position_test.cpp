// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/shared_position.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "daemon/records/map_geometry.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

constexpr std::uint64_t kOwnerEpochNs = 7'000'000'000'000;  // the owner's clock: its own epoch
constexpr double kOwnerLat = 52.1;
constexpr double kOwnerLon = 5.2;

std::uint64_t sender_ns(std::chrono::nanoseconds t) {
  return kOwnerEpochNs + static_cast<std::uint64_t>(t.count());
}

// A motion sample sent at `sent` on the owner's clock with the owner's fix from `fix_at`.
SharedMotionSample sample_with_fix(double speed, double heading_deg, std::chrono::nanoseconds sent,
                                   std::chrono::nanoseconds fix_at,
                                   std::chrono::nanoseconds arrival, std::uint64_t count) {
  SharedMotionSample s{speed, 0.0, sender_ns(sent), arrival, count, {}};
  s.fix = {kOwnerLat, kOwnerLon, heading_deg, io::GnssFixMode::k3D, sender_ns(fix_at), 0};
  return s;
}

// Where the shared fix puts the antenna at `now`, in metres north and east of the owner's fix.
void moved_by(const GnssSample& sample, std::chrono::nanoseconds now, double& north_m,
              double& east_m) {
  const auto at =
      antenna_at(sample.value, std::chrono::duration<double>(now - sample.sample_time).count());
  ASSERT_TRUE(at.has_value());
  local_offset({kOwnerLat, kOwnerLon}, *at, north_m, east_m);
}

// The owner's fix is 0.3 s older than its motion sample; 0.2 s after the sample arrived the
// antenna is 0.5 s x 2 m/s = 1 m along the heading of 60 degrees from the fix.
TEST(SharedPosition, AFixIsCarriedAlongItsHeadingAtTheSharedSpeed) {
  SharedMotionTracker tracker(500ms);
  const auto arrival = 1000s;
  const SharedMotionSample s = sample_with_fix(2.0, 60.0, 10s, 10s - 300ms, arrival, 1);
  tracker.update(s, arrival);
  ASSERT_TRUE(tracker.took_sample());
  const GnssSample fix = shared_gnss_sample(s, tracker);
  EXPECT_EQ(fix.value.mode, io::GnssFixMode::k3D);
  EXPECT_NEAR(static_cast<double>((fix.sample_time - (arrival - 300ms)).count()), 0.0, 1e3)
      << "the fix's time on this board's clock";
  double north = 0;
  double east = 0;
  moved_by(fix, arrival + 200ms, north, east);
  EXPECT_NEAR(north, 1.0 * std::cos(60.0 * M_PI / 180.0), 0.02);
  EXPECT_NEAR(east, 1.0 * std::sin(60.0 * M_PI / 180.0), 0.02);
}

// Samples 50 ms apart, the fastest 5 ms in transit, the last 40 ms: its fix is 35 ms older than
// its arrival says, and is carried for that too (the same estimate that ages the speed).
TEST(SharedPosition, ALateSampleCarriesItsFixForItsExtraAge) {
  SharedMotionTracker tracker(500ms);
  const double speed = 3.0;
  SharedMotionSample s;
  std::chrono::nanoseconds arrival{};
  for (std::uint64_t k = 1; k <= 10; ++k) {
    const auto sent = std::chrono::milliseconds(50 * k);
    arrival = 2000s + sent + (k == 10 ? 40ms : 5ms);
    s = sample_with_fix(speed, 180.0, sent, sent - 100ms, arrival, k);
    tracker.update(s, arrival);
  }
  const GnssSample fix = shared_gnss_sample(s, tracker);
  double north = 0;
  double east = 0;
  moved_by(fix, arrival + 1s, north, east);
  // 100 ms fix age + 35 ms extra age + 1 s since arrival, due south.
  EXPECT_NEAR(north, -speed * 1.135, 0.02);
  EXPECT_NEAR(east, 0.0, 0.01);
}

TEST(SharedPosition, ASampleWithoutAFixIsNoFixAtItsArrival) {
  SharedMotionTracker tracker(500ms);
  SharedMotionSample s{1.5, 10.0, sender_ns(1s), 500s, 1, {}};
  tracker.update(s, 500s);
  const GnssSample fix = shared_gnss_sample(s, tracker);
  EXPECT_EQ(fix.value.mode, io::GnssFixMode::kNone);
  EXPECT_FALSE(fix.value.has_position());
  EXPECT_EQ(fix.sample_time, 500s);
  EXPECT_FALSE(gnss_fix_usable(fix, 500s, 2s));
}

// The owner's samples stop: the last shared fix ages like a receiver's, counted from when it was
// taken (0.1 s before its sample), so gnss_fix_lost comes at the lost-fix timeout.
TEST(SharedPosition, WhenTheSamplesStopTheFixIsLostAtTheTimeout) {
  SharedMotionTracker tracker(500ms);
  LostFixWatch watch(0s, 2s, 60s);
  const auto arrival = 100s;
  const SharedMotionSample s = sample_with_fix(2.0, 0.0, 10s, 10s - 100ms, arrival, 1);
  tracker.update(s, arrival);
  const GnssSample fix = shared_gnss_sample(s, tracker);
  EXPECT_TRUE(gnss_fix_usable(fix, arrival, 2s));
  EXPECT_FALSE(watch.lost(fix, arrival));
  EXPECT_FALSE(watch.lost(fix, arrival + 1890ms));
  EXPECT_TRUE(watch.lost(fix, arrival + 1910ms));
}

TEST(SharedPosition, AFixOutsideTheGlobeIsNone) {
  SharedFix fix{95.0, 5.0, 0.0, io::GnssFixMode::k2D, 1, 0};
  EXPECT_FALSE(fix.has_position());
  fix.latitude_deg = 45.0;
  EXPECT_TRUE(fix.has_position());
}

}  // namespace
}  // namespace weedspray::daemon
