// SPDX-License-Identifier: Apache-2.0
// The control loop's duty step: the rate law's flows become the lines' duties at the filtered
// pressure, snapped to the quantiser's levels, clamped by the band; not spraying closes every
// valve and restarts the quantisers; the flow trim scales the modulated duties.
#include "control/nozzle_command_step.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>

namespace weedspray::control {
namespace {

constexpr double kCycleS = 0.002;

struct Boom {
  std::array<NozzleLine, 3> lines{};
  std::array<double, 3> flows{0.4, 0.1, 0.0};
  double pulses = 0.0;
};

NozzleCommandInputs inputs(const Boom& boom, double pressure_mpa, bool spraying = true) {
  NozzleCommandInputs in;
  in.dt_s = kCycleS;
  in.spraying = spraying;
  in.law.min_duty_pct = 20.0;
  in.law.max_duty_pct = 80.0;
  in.pressure_mpa = pressure_mpa;
  in.setpoint_mpa = pressure_mpa;
  in.pulses = static_cast<std::uint64_t>(boom.pulses);
  in.pulses_per_litre = 1000.0;
  in.target_flow_l_per_min = boom.flows;
  in.lines = boom.lines;
  return in;
}

NozzleCommandConfig three_nozzles() {
  NozzleCommandConfig config;
  config.nozzles = 3;
  return config;
}

TEST(NozzleCommandStep, DutiesAreTheLinesAtTheFilteredPressureInsideTheBand) {
  Boom boom;
  NozzleCommandStep step(three_nozzles());
  const NozzleCommandOutputs& out = step.step(inputs(boom, 0.4));
  // At the calibration pressure the duty is the line's: (0.4 - 0.217) / 0.00393.
  EXPECT_NEAR(out.duty_pct[0], (0.4 - 0.217) / 0.00393, 1e-9);
  EXPECT_DOUBLE_EQ(out.duty_pct[1], 0.0);  // below the line's intercept: closed
  EXPECT_DOUBLE_EQ(out.duty_pct[2], 0.0);  // nothing asked
  EXPECT_NEAR(out.open_fraction, out.duty_pct[0] / 300.0, 1e-12);
  // One read at a quarter of the pressure moves the compensation by about 2 % of the step (the
  // 0.1 s filter), not to sqrt(4) x the flow.
  const NozzleCommandOutputs& after = step.step(inputs(boom, 0.1));
  EXPECT_NEAR(after.compensation_pressure_mpa, 0.4 - 0.3 * (1.0 - std::exp(-0.02)), 1e-9);
  EXPECT_LT(after.duty_pct[0], 80.0);
  // Held at 0.1 MPa for a second the line needs twice the flow: past the band, held open.
  for (int i = 0; i < 500; ++i) step.step(inputs(boom, 0.1));
  EXPECT_NEAR(step.outputs().compensation_pressure_mpa, 0.1, 1e-4);
  EXPECT_DOUBLE_EQ(step.outputs().duty_pct[0], 100.0);
}

TEST(NozzleCommandStep, NotSprayingClosesEveryValve) {
  Boom boom;
  NozzleCommandStep step(three_nozzles());
  const NozzleCommandOutputs& out = step.step(inputs(boom, 0.4, false));
  for (std::size_t n = 0; n < 3; ++n) EXPECT_DOUBLE_EQ(out.duty_pct[n], 0.0);
  EXPECT_DOUBLE_EQ(out.open_fraction, 0.0);
}

TEST(NozzleCommandStep, TheQuantiserSnapsAndRestartsWhenTheNozzleCloses) {
  NozzleCommandConfig config = three_nozzles();
  config.quantiser_levels_pct = {0.0, 20.0, 50.0, 80.0, 100.0};
  config.quantiser_level_count = 5;
  config.quantiser_hysteresis_pct = 10.0;
  NozzleCommandStep step(config);
  Boom boom;
  const NozzleLine& line = boom.lines[0];
  const auto flow_at = [&](double duty) {
    return line.slope_l_per_min_per_pct * duty + line.intercept_l_per_min;
  };
  boom.flows = {flow_at(45.0), 0.0, 0.0};
  EXPECT_DOUBLE_EQ(step.step(inputs(boom, 0.4)).duty_pct[0], 50.0);
  boom.flows[0] = flow_at(78.0);
  EXPECT_DOUBLE_EQ(step.step(inputs(boom, 0.4)).duty_pct[0], 80.0);
  // 62 % is within half a step plus the hysteresis of the 80 % level: it stays there.
  boom.flows[0] = flow_at(62.0);
  EXPECT_DOUBLE_EQ(step.step(inputs(boom, 0.4)).duty_pct[0], 80.0);
  // Closed, then asked for 62 % again: a fresh quantiser takes the nearest level.
  boom.flows[0] = 0.0;
  EXPECT_DOUBLE_EQ(step.step(inputs(boom, 0.4)).duty_pct[0], 0.0);
  boom.flows[0] = flow_at(62.0);
  EXPECT_DOUBLE_EQ(step.step(inputs(boom, 0.4)).duty_pct[0], 50.0);
  // The same after a stop.
  boom.flows[0] = flow_at(78.0);
  step.step(inputs(boom, 0.4));
  step.step(inputs(boom, 0.4, false));
  boom.flows[0] = flow_at(62.0);
  EXPECT_DOUBLE_EQ(step.step(inputs(boom, 0.4)).duty_pct[0], 50.0);
}

TEST(NozzleCommandStep, TheTrimScalesModulatedDutiesAgainstTheMeter) {
  Boom boom;
  for (auto& line : boom.lines) line.full_open_flow_l_per_min = 0.7;
  boom.flows = {0.4, 0.35, 0.0};
  NozzleCommandStep step(three_nozzles());
  double law_duty = 0.0;
  for (int i = 0; i < static_cast<int>(30.0 / kCycleS); ++i) {
    NozzleCommandInputs in = inputs(boom, 0.4);
    in.trim = true;
    const NozzleCommandOutputs& out = step.step(in);
    law_duty = out.law_duty_pct[0];
    // The nozzles spray 10 % more than their lines promise at the duties commanded.
    for (std::size_t n = 0; n < 3; ++n)
      boom.pulses +=
          1.1 * promised_flow_l_per_min(boom.lines[n], out.duty_pct[n], 0.4) / 60.0 * kCycleS * 1e3;
  }
  EXPECT_TRUE(step.outputs().trim.active);
  EXPECT_NEAR(step.outputs().trim.correction, 1.0 / 1.1, 0.01);
  EXPECT_LT(step.outputs().duty_pct[0], law_duty);
  // A new calibration: the correction starts afresh.
  step.reset_trim();
  NozzleCommandInputs in = inputs(boom, 0.4);
  in.trim = true;
  EXPECT_DOUBLE_EQ(step.step(in).trim.correction, 1.0);
}

// A flow between the band's top and the held-open flow: whole PWM periods alternate between
// held open and the band's top, so the flow promised over time is the target; without the
// grid the valve is held open (the old clamp) and sprays the held-open flow.
TEST(NozzleCommandStep, AFlowAboveTheBandAlternatesWholePeriodsToItsMean) {
  NozzleCommandConfig config = three_nozzles();
  config.pwm_period_s = 0.2;  // 5 Hz
  config.phase_offset_s = {0.0, 0.2 / 3.0, 0.4 / 3.0};
  Boom boom;
  for (auto& line : boom.lines) line.full_open_flow_l_per_min = 0.60;
  const double top = flow_for_duty_l_per_min(boom.lines[0], 80.0, 0.4);  // 0.5314
  const double target = top + 0.3 * (0.60 - top);
  boom.flows = {target, 0.0, 0.0};
  const auto mean_flow = [&](bool grid, std::uint32_t& alternating) {
    NozzleCommandStep step(config);
    double litres = 0.0;
    double duty_changes = 0.0;
    double last_duty = -1.0;
    const int cycles = static_cast<int>(20.0 / kCycleS);
    for (int i = 0; i < cycles; ++i) {
      NozzleCommandInputs in = inputs(boom, 0.4);
      in.schedule_time_s = grid ? i * kCycleS : -1.0;
      const NozzleCommandOutputs& out = step.step(in);
      alternating |= out.alternating_mask;
      litres += promised_flow_l_per_min(boom.lines[0], out.duty_pct[0], 0.4) * kCycleS;
      if (out.duty_pct[0] != last_duty) duty_changes += 1.0;
      last_duty = out.duty_pct[0];
      EXPECT_TRUE(out.duty_pct[0] == 100.0 || (grid && out.duty_pct[0] == 80.0)) << out.duty_pct[0];
    }
    // The level changes only at period starts: at most one change per period.
    EXPECT_LE(duty_changes, 20.0 / 0.2 + 1.0);
    return litres / (cycles * kCycleS);
  };
  std::uint32_t alternating = 0;
  EXPECT_NEAR(mean_flow(true, alternating), target, 0.002 * target);
  EXPECT_EQ(alternating, 1U);
  alternating = 0;
  EXPECT_NEAR(mean_flow(false, alternating), 0.60, 1e-9);
  EXPECT_EQ(alternating, 0U);
}

TEST(NozzleCommandStep, RefusesABadNozzleCount) {
  NozzleCommandConfig config;
  config.nozzles = 0;
  EXPECT_THROW(NozzleCommandStep{config}, std::invalid_argument);
  config.nozzles = kMaxCommandNozzles + 1;
  EXPECT_THROW(NozzleCommandStep{config}, std::invalid_argument);
}

}  // namespace
}  // namespace weedspray::control
