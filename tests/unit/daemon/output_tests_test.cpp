// SPDX-License-Identifier: Apache-2.0
// The commissioning checks (sprayctl test valve / pump): what they command, what they report,
// and that they are guarded as the calibrations are.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "daemon/sprayer/calibration_run.hpp"

namespace weedspray::daemon {
namespace {

constexpr double kTick = 0.05;  // the daemon's main loop, 20 Hz

TEST(ValveTest, HoldsOnlyTheNamedValveThenReportsTheMetersFlow) {
  CalibrationRun run(4);
  ASSERT_EQ(run.start_valve_test(2, 60.0, 6.0, 10.0, 1000, 8500.0), "");
  EXPECT_TRUE(run.running()) << "the pump must run for a valve test";
  EXPECT_EQ(run.state(), CalibrationState::kValveTest);
  for (std::size_t i = 0; i < io::kMaxValves; ++i)
    EXPECT_EQ(run.duties()[i], i == 2 ? 60.0 : 0.0) << "valve " << i;
  EXPECT_NE(run.start_catch_test(10.0, 10.0, 1000), "") << "a calibration started over it";
  // 0.5 L/min through the meter for 6 s: 0.05 L, 425 pulses.
  double t = 10.0;
  std::uint64_t pulses = 1000;
  double litres = 0.0;
  while (run.running() && t < 30.0) {
    t += kTick;
    litres += 0.5 / 60.0 * kTick;
    pulses = 1000 + static_cast<std::uint64_t>(litres * 8500.0);
    run.update(t, pulses);
  }
  EXPECT_NEAR(t, 16.0, kTick + 1e-9);
  EXPECT_EQ(run.state(), CalibrationState::kDone);
  for (double d : run.duties()) EXPECT_EQ(d, 0.0);
  EXPECT_NE(run.message().find("nozzle 2 at 60 % for 6 s"), std::string::npos) << run.message();
  EXPECT_NE(run.message().find("0.500 L/min by the meter"), std::string::npos) << run.message();
}

TEST(ValveTest, NoPulsesIsSaidPlainlyAndBadArgumentsAreRefused) {
  CalibrationRun run(4);
  ASSERT_EQ(run.start_valve_test(0, 100.0, 1.0, 0.0, 50, 8500.0), "");
  run.update(1.0, 50);
  EXPECT_NE(run.message().find("NO pulses"), std::string::npos) << run.message();
  EXPECT_NE(run.start_valve_test(4, 50.0, 5.0, 2.0, 0, 8500.0).find("does not exist"),
            std::string::npos);
  EXPECT_NE(run.start_valve_test(0, 0.0, 5.0, 2.0, 0, 8500.0), "");
  EXPECT_NE(run.start_valve_test(0, 50.0, 61.0, 2.0, 0, 8500.0), "");
  EXPECT_FALSE(run.running());
  // Without a meter the test still runs, and says so.
  ASSERT_EQ(run.start_valve_test(1, 40.0, 1.0, 3.0, 0, 0.0), "");
  run.update(4.0, 0);
  EXPECT_NE(run.message().find("no flow meter"), std::string::npos) << run.message();
}

TEST(PumpTest, RunsThePumpWithEveryValveClosedAndSaysWhenTheSetPointCame) {
  CalibrationRun run(4);
  ASSERT_EQ(run.start_pump_test(5.0, 0.0, 0.4), "");
  EXPECT_TRUE(run.running());
  for (double d : run.duties()) EXPECT_EQ(d, 0.0);
  // The pressure rises 0.2 MPa/s: 95 % of 0.4 MPa (0.38) after 1.9 s.
  double t = 0.0;
  while (run.running() && t < 10.0) {
    t += kTick;
    run.observe_pressure(t, std::min(0.2 * t, 0.41));
    run.update(t, 0);
  }
  EXPECT_EQ(run.state(), CalibrationState::kDone);
  EXPECT_NE(run.message().find("reached after 1.9 s (peak 0.410 MPa)"), std::string::npos)
      << run.message();
}

TEST(PumpTest, ASetPointNeverReachedNamesWhatToCheck) {
  CalibrationRun run(4);
  ASSERT_EQ(run.start_pump_test(2.0, 0.0, 0.4), "");
  for (double t = kTick; run.running(); t += kTick) {
    run.observe_pressure(t, 0.05);
    run.update(t, 0);
  }
  EXPECT_NE(run.message().find("NOT reached in 2 s (highest 0.050 MPa)"), std::string::npos)
      << run.message();
  EXPECT_NE(run.message().find("sprayctl inputs"), std::string::npos);
}

TEST(PumpTest, StopCancelsItAndClosesEverything) {
  CalibrationRun run(4);
  ASSERT_EQ(run.start_valve_test(1, 100.0, 30.0, 0.0, 0, 8500.0), "");
  run.cancel("Stop");
  EXPECT_FALSE(run.running());
  EXPECT_EQ(run.state(), CalibrationState::kCancelled);
  for (double d : run.duties()) EXPECT_EQ(d, 0.0);
  EXPECT_EQ(run.message(), "valve_test cancelled: Stop");
}

}  // namespace
}  // namespace weedspray::daemon
