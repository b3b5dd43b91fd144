// SPDX-License-Identifier: Apache-2.0
#include "control/pressure_controller.hpp"

#include <gtest/gtest.h>

namespace weedspray::control {
namespace {

FuzzyPidConfig loop_config() {
  FuzzyPidConfig config;
  config.base.gains = {0.8, 2.0, 0.01};
  config.base.output_min = 0.0;
  config.base.output_max = 1.0;
  config.correction_weights = {0.05, 0.1, 0.001};
  config.error_range = 0.4;
  return config;
}

TEST(PressureController, PidModeMatchesAPlainPid) {
  const FuzzyPidConfig config = loop_config();
  PressureController controller(PressureControlMode::kPid, config);
  Pid plain(config.base);
  double y = 0.0;
  for (int i = 0; i < 200; ++i) {
    const double u = controller.update(0.2, y, 0.01);
    ASSERT_DOUBLE_EQ(u, plain.update(0.2, y, 0.01));
    y += (0.4 * u - y) * 0.05;
  }
  EXPECT_EQ(controller.mode(), PressureControlMode::kPid);
  EXPECT_DOUBLE_EQ(controller.current_gains().kp, 0.8);
}

TEST(PressureController, FuzzyModeMatchesAFuzzyPidAndAdaptsGains) {
  const FuzzyPidConfig config = loop_config();
  PressureController controller(PressureControlMode::kFuzzyPid, config);
  FuzzyPid fuzzy(config);
  double y = 0.0;
  for (int i = 0; i < 200; ++i) {
    const double u = controller.update(0.2, y, 0.01);
    ASSERT_DOUBLE_EQ(u, fuzzy.update(0.2, y, 0.01));
    y += (0.4 * u - y) * 0.05;
  }
  // Far below the set-point at the start the gains differ from the base ones.
  PressureController fresh(PressureControlMode::kFuzzyPid, config);
  fresh.update(0.2, 0.0, 0.01);
  EXPECT_NE(fresh.current_gains().kp, 0.8);
}

TEST(PressureController, EnableDisableResetForward) {
  PressureController controller(PressureControlMode::kFuzzyPid, loop_config());
  controller.disable();
  EXPECT_FALSE(controller.enabled());
  controller.enable(0.5, 0.2, 0.2);
  EXPECT_TRUE(controller.enabled());
  EXPECT_NEAR(controller.update(0.2, 0.2, 0.01), 0.5, 1e-12);
  controller.reset();
  EXPECT_DOUBLE_EQ(controller.output(), 0.0);
}

}  // namespace
}  // namespace weedspray::control
