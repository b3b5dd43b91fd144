// SPDX-License-Identifier: Apache-2.0
// The daemon's online flow trim on the simulated machine: it follows the line meter (a meter
// that starts counting 10 % more pulses per litre makes it take 10 % off the nozzles' flows),
// and a new calibration (a new meter K or nozzle line, as `sprayctl calibrate` publishes)
// starts it afresh at 1, since its correction was relative to the old one.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "sim/plant/hydraulic_plant.hpp"
#include "tests/sim/daemon/run_until.hpp"
#include "tests/sim/daemon/spraying_machine.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

TEST(FlowTrim, FollowsAMeterDriftAndStartsAfreshOnANewCalibration) {
  // At 1 m/s the rate law keeps most nozzles below 100 % (a nozzle held open has no measured
  // full-open flow in the daemon, and a window with one holds the trim).
  SprayingMachine m(1.0);
  m.start();
  // As calibrated (the configured lines against the simulated nozzles): let it settle.
  run_until(
      m.backends, [] { return false; }, 15s);
  const ControlStatus settled = m.sprayer->control();
  EXPECT_TRUE(settled.flow_trim_active);
  const double before = settled.flow_trim_correction;
  ASSERT_GT(before, 0.85);
  ASSERT_LT(before, 1.15);

  m.backends.with_plant([](sim::plant::HydraulicPlant& p) { p.set_meter_drift(0.10); });
  const double expected = before / 1.10;
  const bool followed = run_until(
      m.backends,
      [&] { return std::abs(m.sprayer->control().flow_trim_correction / expected - 1.0) < 0.02; },
      40s);
  EXPECT_TRUE(followed) << "correction " << m.sprayer->control().flow_trim_correction
                        << ", expected " << expected << " (" << before << " before the drift)";

  // The catch test found the drifted meter's K: the trim starts again from 1.
  LiveParams recalibrated = m.params;
  recalibrated.flow_pulses_per_litre *= 1.10;
  m.sprayer->set_params(recalibrated);
  run_until(
      m.backends, [] { return false; }, 200ms);
  EXPECT_EQ(m.sprayer->control().flow_trim_correction, 1.0);
  m.sprayer->stop();
}

}  // namespace
}  // namespace weedspray::daemon
