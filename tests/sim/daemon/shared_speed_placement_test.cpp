// SPDX-License-Identifier: Apache-2.0
// Placement of a board that takes its speed from another (speed.source = "fleet"), in the
// placement test's terms (placement_harness.hpp): the owning board measures the plant's true
// speed and odometer every 50 ms (fleet.motion_rate_hz = 20) with its own clock, whose epoch is
// not this board's; each sample reaches FeedSharedMotion after a transit of 5-40 ms, in order
// (one TCP connection through the broker). With the speed swinging 0.5-2.5 m/s every spray
// edge must still lie within 5 cm of the ground its frame imaged.
// PLACEMENT_SHARED_LATENCY_MS in the environment sets the longest transit (ms).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <deque>
#include <random>

#include "sim/plant/hydraulic_plant.hpp"
#include "tests/sim/daemon/placement_harness.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

// What the owning board's bridge published, and when this board's bridge hands it on.
struct InTransit {
  double speed_m_per_s;
  double distance_m;
  std::uint64_t sender_time_ns;
  Nanos delivery;
};

class SharedMotionLink {
 public:
  SharedMotionLink(Nanos period, double min_transit_ms, double max_transit_ms)
      : period_(period), transit_ms_(min_transit_ms, max_transit_ms) {}

  // One tick of the test's loop: the owner samples when its period is due; samples whose
  // transit is over are fed to the sprayer.
  void tick(Sprayer& sprayer, Backends& backends) {
    const Nanos now = backends.clock->now();
    if (now >= next_sample_) {
      next_sample_ = now + period_;
      InTransit sample{};
      backends.with_plant([&](sim::plant::HydraulicPlant& p) {
        sample.speed_m_per_s = p.ground_speed_m_per_s();
        sample.distance_m = p.distance_m();
      });
      sample.sender_time_ns = kOwnerEpochNs + static_cast<std::uint64_t>(now.count());
      const auto transit = std::chrono::duration_cast<Nanos>(
          std::chrono::duration<double, std::milli>(transit_ms_(random_)));
      // Over one connection a sample never overtakes the one before it.
      sample.delivery = std::max(now + transit, last_delivery_);
      last_delivery_ = sample.delivery;
      in_transit_.push_back(sample);
    }
    while (!in_transit_.empty() && in_transit_.front().delivery <= now) {
      const InTransit& s = in_transit_.front();
      sprayer.feed_shared_motion(s.speed_m_per_s, s.distance_m, s.sender_time_ns);
      ++delivered_;
      in_transit_.pop_front();
    }
  }
  [[nodiscard]] std::size_t delivered() const { return delivered_; }

 private:
  // The owner's clock counts from its own boot: 3 hours ahead of this board's.
  static constexpr std::uint64_t kOwnerEpochNs = 10'800'000'000'000;
  Nanos period_;
  std::mt19937 random_{36};
  std::uniform_real_distribution<double> transit_ms_;
  Nanos next_sample_{};
  Nanos last_delivery_{};
  std::deque<InTransit> in_transit_;
  std::size_t delivered_ = 0;
};

TEST(SharedSpeedPlacement, SprayWithinFiveCmOnAnotherBoardsSpeedAfterJitteryTransit) {
  Config config = placement_config();
  config.speed.source = "fleet";
  config.fleet.speed_from = "owner";
  double max_transit_ms = 40;
  if (const char* ms = std::getenv("PLACEMENT_SHARED_LATENCY_MS")) max_transit_ms = std::atof(ms);
  SharedMotionLink link(50ms, 5, max_transit_ms);
  const PlacementFigures figures = run_placement(
      config, [&](Sprayer& sprayer, Backends& backends, double) { link.tick(sprayer, backends); });
  std::printf("shared speed: %zu samples delivered, transit 5-%.0f ms\n", link.delivered(),
              max_transit_ms);
  EXPECT_GT(link.delivered(), 400U) << "24 s at 20 Hz";
  EXPECT_LE(figures.max_cm, 5.0);
}

}  // namespace
}  // namespace weedspray::daemon
