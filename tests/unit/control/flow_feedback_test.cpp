#include "control/flow_feedback.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace weedspray::control {
namespace {

TEST(FlowTrim, IntegratesTheRelativeError) {
  FlowTrim trim(FlowTrimConfig{});  // gain 0.2 /s, rate limit 0.05 /s
  double c = 1.0;
  for (int i = 0; i < 100; ++i) c = trim.update(1.0, 0.9, 0.5, 0.01);  // 10 % low for 1 s
  EXPECT_FALSE(trim.frozen());
  EXPECT_NEAR(c, 1.0 + 0.2 * 0.1 * 1.0, 1e-9);
}

TEST(FlowTrim, RateLimited) {
  FlowTrim trim(FlowTrimConfig{});
  double c = 1.0;
  for (int i = 0; i < 100; ++i) c = trim.update(1.0, 0.5, 0.5, 0.01);  // 0.2 * 0.5 = 0.1 /s
  EXPECT_NEAR(c, 1.05, 1e-9);
}

TEST(FlowTrim, Bounded) {
  FlowTrim trim(FlowTrimConfig{});
  for (int i = 0; i < 100000; ++i) trim.update(1.0, 0.2, 0.5, 0.01);
  EXPECT_DOUBLE_EQ(trim.correction(), 1.3);
  for (int i = 0; i < 100000; ++i) trim.update(1.0, 3.0, 0.5, 0.01);
  EXPECT_DOUBLE_EQ(trim.correction(), 0.7);
}

TEST(FlowTrim, FrozenWithoutFlowOrWithClosedValves) {
  FlowTrim trim(FlowTrimConfig{});
  for (int i = 0; i < 100; ++i) trim.update(1.0, 0.8, 0.5, 0.01);
  const double held = trim.correction();
  EXPECT_GT(held, 1.0);
  EXPECT_DOUBLE_EQ(trim.update(0.01, 0.0, 0.5, 0.01), held);  // nothing requested
  EXPECT_TRUE(trim.frozen());
  EXPECT_DOUBLE_EQ(trim.update(1.0, 0.0, 0.05, 0.01), held);  // valves mostly closed
  EXPECT_TRUE(trim.frozen());
  EXPECT_DOUBLE_EQ(trim.update(1.0, std::nan(""), 0.5, 0.01), held);
  trim.reset();
  EXPECT_DOUBLE_EQ(trim.correction(), 1.0);
}

TEST(FlowTrim, ClosedLoopConvergesToTheMeterGain) {
  // The line delivers 8 % less than the law predicts: the trim must settle at 1 / 0.92.
  FlowTrim trim(FlowTrimConfig{});
  const double requested = 1.2;
  for (int i = 0; i < 6000; ++i) {  // 60 s at 100 Hz
    const double measured = 0.92 * requested * trim.correction();
    trim.update(requested, measured, 0.6, 0.01);
  }
  EXPECT_NEAR(trim.correction(), 1.0 / 0.92, 1e-3);
}

TEST(FlowTrim, RejectsBadConfig) {
  FlowTrimConfig config;
  config.min_correction = 1.1;
  EXPECT_THROW(FlowTrim{config}, std::invalid_argument);
  config = FlowTrimConfig{};
  config.max_rate_per_s = -1.0;
  EXPECT_THROW(FlowTrim{config}, std::invalid_argument);
}

}  // namespace
}  // namespace weedspray::control
