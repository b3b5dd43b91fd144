// SPDX-License-Identifier: Apache-2.0
// Several cameras on one board: each steers its own contiguous range of nozzles.
#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

#include "daemon/backends/backends.hpp"
#include "daemon/sprayer/sprayer.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

TEST(MultiCamera, EachCameraSteersItsOwnNozzles) {
  Config config = default_config();
  config.boom.nozzles = 6;
  ASSERT_EQ(config.cameras.size(), 1U);
  config.cameras.push_back(config.cameras[0]);
  config.cameras[0].first_nozzle = 0;
  config.cameras[0].nozzle_count = 3;
  config.cameras[1].first_nozzle = 3;
  config.cameras[1].nozzle_count = 3;
  config.sim.speed_profile = "constant";
  config.sim.speed_max_m_per_s = 2.0;
  Options options;
  options.sim = true;

  Backends backends = make_sim_backends(config, options);
  ASSERT_EQ(backends.cameras.size(), 2U);
  Sprayer sprayer(config, backends);
  ASSERT_EQ(sprayer.camera_count(), 2U);
  LiveParams params = live_params_from(config);
  params.pump_enabled = true;
  params.valves_enabled = true;
  sprayer.set_params(params);
  backends.drive_world(0);
  sprayer.start();

  // Camera 1's ground reaches its nozzles after camera-to-nozzle distance + footprint: run
  // until both halves of the boom have been steered, for at most 20 s.
  std::array<double, 6> most_density{};
  std::array<double, 6> most_duty{};
  const auto start = backends.clock->now();
  while (backends.clock->now() - start < 20s) {
    const double t = std::chrono::duration<double>(backends.clock->now() - start).count();
    backends.drive_world(t);
    const ControlStatus c = sprayer.control();
    for (std::size_t n = 0; n < 6; ++n) {
      most_density[n] = std::max(most_density[n], c.density[n]);
      most_duty[n] = std::max(most_duty[n], c.duty_pct[n]);
    }
    if (*std::min_element(most_duty.begin(), most_duty.end()) > 0 && t > 3.0) break;
    std::this_thread::sleep_for(5ms);
  }
  const CameraStatus first = sprayer.camera(0);
  const CameraStatus second = sprayer.camera(1);
  sprayer.stop();

  EXPECT_GT(first.frames, 3U);
  EXPECT_GT(second.frames, 3U);
  for (std::size_t n = 0; n < 6; ++n) {
    EXPECT_GT(most_density[n], 0.0) << "nozzle " << n << " never saw its camera's plants";
    EXPECT_GT(most_duty[n], 0.0) << "nozzle " << n << " never sprayed";
  }
}

}  // namespace
}  // namespace weedspray::daemon
