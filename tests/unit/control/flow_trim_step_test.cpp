// SPDX-License-Identifier: Apache-2.0
// The control loop's flow-trim step: a boom whose meter counts more than the lines promise is
// trimmed down inside the law's band; closed and held-open nozzles are left alone; not spraying
// holds the correction.
#include "control/flow_trim_step.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>

namespace weedspray::control {
namespace {

constexpr double kDt = 0.002;
constexpr double kPulsesPerLitre = 1000.0;

struct Boom {
  std::array<NozzleLine, 4> lines{};
  std::array<double, 4> law_duty{50.0, 40.0, 0.0, 100.0};
  std::array<double, 4> duty{};
  double pulses = 0.0;
};

// One cycle: the nozzles spray `true_ratio` x their lines' promise at the commanded duties.
const FlowTrimStepOutputs& cycle(FlowTrimStep& step, Boom& boom, double true_ratio,
                                 bool spraying = true) {
  boom.duty = boom.law_duty;
  FlowTrimStepInputs in;
  in.dt_s = kDt;
  in.spraying = spraying;
  in.pressure_mpa = 0.4;
  in.setpoint_mpa = 0.4;
  in.compensation_pressure_mpa = 0.4;
  in.pulses = static_cast<std::uint64_t>(boom.pulses);
  in.pulses_per_litre = kPulsesPerLitre;
  in.duty_pct = boom.duty;
  in.lines = boom.lines;
  in.min_duty_pct = 20.0;
  in.max_duty_pct = 80.0;
  const FlowTrimStepOutputs& out = step.step(in);
  for (std::size_t n = 0; n < boom.duty.size(); ++n)
    boom.pulses += true_ratio * promised_flow_l_per_min(boom.lines[n], boom.duty[n], 0.4) / 60.0 *
                   kDt * kPulsesPerLitre;
  return out;
}

TEST(FlowTrimStep, TrimsAMeterThatCountsMoreInsideTheBand) {
  Boom boom;
  for (auto& line : boom.lines) line.full_open_flow_l_per_min = 0.7;
  FlowTrimStep step;
  for (int i = 0; i < static_cast<int>(30.0 / kDt); ++i) cycle(step, boom, 1.1);
  EXPECT_TRUE(step.outputs().active);
  EXPECT_NEAR(step.outputs().correction, 1.0 / 1.1, 0.01);
  EXPECT_LT(boom.duty[0], 50.0);
  EXPECT_GE(boom.duty[1], 20.0);
  EXPECT_DOUBLE_EQ(boom.duty[2], 0.0);    // closed stays closed
  EXPECT_DOUBLE_EQ(boom.duty[3], 100.0);  // held open stays open
  // Not spraying: the correction holds, the trim is inactive.
  const double held = step.outputs().correction;
  for (int i = 0; i < 1000; ++i) cycle(step, boom, 2.0, false);
  EXPECT_FALSE(step.outputs().active);
  EXPECT_DOUBLE_EQ(step.outputs().correction, held);
  step.reset();
  EXPECT_DOUBLE_EQ(step.correction(), 1.0);
}

TEST(FlowTrimStep, AHeldOpenNozzleWithoutAFullOpenFlowFreezesTheTrim) {
  Boom boom;  // no full-open flows: nozzle 3 at 100 % promises nothing known
  FlowTrimStep step;
  for (int i = 0; i < static_cast<int>(30.0 / kDt); ++i) cycle(step, boom, 1.1);
  EXPECT_FALSE(step.outputs().active);
  EXPECT_DOUBLE_EQ(step.outputs().correction, 1.0);
}

TEST(PressureFilter, FollowsWithItsTimeConstant) {
  PressureFilter filter;
  EXPECT_DOUBLE_EQ(filter.update(0.2, 0.01), 0.2);  // the first reading as it is
  for (int i = 0; i < 10; ++i) filter.update(0.3, 0.01);
  EXPECT_NEAR(filter.value(), 0.3 - 0.1 * std::exp(-1.0), 1e-9);  // one time constant
}

}  // namespace
}  // namespace weedspray::control
