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

TEST(FlowTrim, ErrorIsNormalisedByTheTrimmableShare) {
  // Three nozzles held at 100 % (0.9 L/min) and one modulated nozzle asked for 0.3 L/min that
  // gives 10 % too much: the error is the modulated nozzle's, not diluted by the other three.
  FlowTrimConfig config;
  config.max_rate_per_s = 10.0;  // no rate limit in the way
  config.min_trimmable_fraction = 0.05;
  FlowTrim diluted(config);
  FlowTrim shared(config);
  FlowTrimInput in;
  in.requested_total_l_per_min = 3.0;
  in.trimmable_l_per_min = 0.3;
  in.measured_total_l_per_min = 3.03;
  in.open_fraction = 0.85;
  in.dt_s = 1.0;
  shared.update(in);
  diluted.update(3.0, 3.03, 0.85, 1.0);
  EXPECT_NEAR(shared.correction() - 1.0, -config.gain_per_s * 0.1, 1e-12);
  EXPECT_NEAR(diluted.correction() - 1.0, -config.gain_per_s * 0.01, 1e-12);
}

TEST(FlowTrim, WoundUpTrimUnwindsInSecondsWithNozzlesHeldOpen) {
  // Start wound up at the lower bound; the modulated nozzle's true gain is 1, so the trim must
  // come back to 1 within 30 s although three nozzles are held fully open.
  FlowTrimConfig config;
  config.min_correction = 0.7;
  config.min_trimmable_fraction = 0.05;
  FlowTrim trim(config);
  FlowTrimInput in;
  in.requested_total_l_per_min = 3.0;
  in.trimmable_l_per_min = 0.3;
  in.open_fraction = 0.85;
  in.dt_s = 1.0;
  for (int i = 0; i < 40; ++i) {  // wind it up: the meter reads far too much
    in.measured_total_l_per_min = 4.0;
    trim.update(in);
  }
  ASSERT_NEAR(trim.correction(), 0.7, 1e-12);
  for (int i = 0; i < 30; ++i) {
    in.measured_total_l_per_min = 2.7 + 0.3 * trim.correction();
    trim.update(in);
  }
  EXPECT_NEAR(trim.correction(), 1.0, 0.01);
}

TEST(FlowTrim, FreezesWhilePressureIsOffSetPointOrNothingIsTrimmable) {
  FlowTrim trim(FlowTrimConfig{});
  FlowTrimInput in;
  in.requested_total_l_per_min = 1.0;
  in.trimmable_l_per_min = 1.0;
  in.measured_total_l_per_min = 0.5;
  in.open_fraction = 0.5;
  in.dt_s = 1.0;
  in.pressure_error_fraction = 0.2;  // start-up in the window
  EXPECT_DOUBLE_EQ(trim.update(in), 1.0);
  EXPECT_TRUE(trim.frozen());
  in.pressure_error_fraction = 0.0;
  in.trimmable_l_per_min = 0.0;  // all nozzles closed or fully open
  EXPECT_DOUBLE_EQ(trim.update(in), 1.0);
  EXPECT_TRUE(trim.frozen());
  in.trimmable_l_per_min = 0.2;  // below min_trimmable_fraction (0.3) of the request
  EXPECT_DOUBLE_EQ(trim.update(in), 1.0);
  EXPECT_TRUE(trim.frozen());
  in.trimmable_l_per_min = 1.0;
  EXPECT_GT(trim.update(in), 1.0);
  EXPECT_FALSE(trim.frozen());
}

TEST(FlowTrim, RejectsBadConfig) {
  FlowTrimConfig config;
  config.min_correction = 1.1;
  EXPECT_THROW(FlowTrim{config}, std::invalid_argument);
  config = FlowTrimConfig{};
  config.max_rate_per_s = -1.0;
  EXPECT_THROW(FlowTrim{config}, std::invalid_argument);
  config = FlowTrimConfig{};
  config.max_pressure_error_fraction = 0.0;
  EXPECT_THROW(FlowTrim{config}, std::invalid_argument);
}

TEST(FlowTrimWindows, TimeMeansOverAWindowAndTheMetersPulsesOverItsLength) {
  FlowTrimWindows windows(1.0);
  FlowTrimInput out;
  FlowTrimTick tick;
  tick.pulses = 1000;
  EXPECT_FALSE(windows.tick(0.01, tick, 8500.0, out));  // only starts the window
  // 100 ticks of 10 ms: promised 2.0 L/min for the first half, 1.0 for the second; the meter
  // counts 8500 x 1.5 / 60 pulses over the second.
  bool closed = false;
  for (int i = 1; i <= 100; ++i) {
    tick.promised_l_per_min = i <= 50 ? 2.0 : 1.0;
    tick.trimmable_l_per_min = i <= 50 ? 1.0 : 0.0;
    tick.open_fraction = i <= 50 ? 0.6 : 0.2;
    tick.pressure_error_fraction = i == 30 ? -0.08 : 0.01;
    tick.pulses = 1000 + static_cast<std::uint64_t>(std::lround(8500.0 * 1.5 / 60.0 * i / 100.0));
    closed = windows.tick(0.01, tick, 8500.0, out);
    if (i < 100) {
      ASSERT_FALSE(closed) << i;
    }
  }
  ASSERT_TRUE(closed);
  EXPECT_NEAR(out.requested_total_l_per_min, 1.5, 1e-9);
  EXPECT_NEAR(out.trimmable_l_per_min, 0.5, 1e-9);
  EXPECT_NEAR(out.open_fraction, 0.4, 1e-9);
  EXPECT_NEAR(out.pressure_error_fraction, 0.08, 1e-12);  // the worst tick's, either sign
  EXPECT_NEAR(out.measured_total_l_per_min, 1.5, 0.005);
  EXPECT_NEAR(out.dt_s, 1.0, 1e-9);
  // The next window starts where this one ended: 50 ticks measure only their own pulses.
  for (int i = 1; i <= 100; ++i) {
    tick.pulses += 10;
    closed = windows.tick(0.01, tick, 8500.0, out);
  }
  ASSERT_TRUE(closed);
  EXPECT_NEAR(out.measured_total_l_per_min, 1000.0 / 8500.0 * 60.0, 1e-9);
}

TEST(FlowTrimWindows, ResetStartsAfreshAndAnUnknownMeterFreezesTheTrim) {
  FlowTrimWindows windows(0.5);
  FlowTrimInput out;
  FlowTrimTick tick{1.0, 1.0, 0.5, 0.0, 0};
  windows.tick(0.01, tick, 8500.0, out);
  for (int i = 0; i < 30; ++i) windows.tick(0.01, tick, 8500.0, out);
  windows.reset();  // e.g. spraying stopped: the 0.3 s counted so far are dropped
  tick.pulses = 500;
  EXPECT_FALSE(windows.tick(0.01, tick, 8500.0, out));
  int ticks = 0;
  while (!windows.tick(0.01, tick, 0.0, out)) ++ticks;
  EXPECT_EQ(ticks, 49);  // a whole 0.5 s after the restart
  EXPECT_TRUE(std::isnan(out.measured_total_l_per_min));
  FlowTrim trim(FlowTrimConfig{});
  trim.update(out);
  EXPECT_TRUE(trim.frozen());
}

// One tick with a nozzle held open whose full-open flow nobody measured (the daemon's
// configured and calibrated lines stop at the sweep's top duty) makes the whole window's
// promise unknown: the trim holds, and calibration_drift's measure skips it.
TEST(FlowTrimWindows, AHeldOpenNozzleWithoutAMeasuredFullFlowMakesTheWindowUnusable) {
  FlowTrimWindows windows(0.1);
  FlowTrimInput out;
  FlowTrimTick tick{1.0, 0.6, 0.7, 0.0, 0};
  windows.tick(0.01, tick, 8500.0, out);
  for (int i = 1; i <= 10; ++i) {
    tick.pulses = static_cast<std::uint64_t>(i) * 2;  // ~1.0 L/min
    tick.promise_known = i != 4;
    if (windows.tick(0.01, tick, 8500.0, out)) break;
  }
  EXPECT_FALSE(out.promise_known);
  FlowTrim trim(FlowTrimConfig{});
  FlowTrimInput half = out;
  half.measured_total_l_per_min = 0.5;  // would move it a lot if it counted
  trim.update(half);
  EXPECT_TRUE(trim.frozen());
  EXPECT_EQ(trim.correction(), 1.0);
  half.promise_known = true;  // the same window with the promise known: it moves
  trim.update(half);
  EXPECT_FALSE(trim.frozen());
  EXPECT_GT(trim.correction(), 1.0);
  CalibrationRatio ratio(FlowTrimConfig{}, 60.0, 0.05);
  ratio.update(out);
  EXPECT_FALSE(ratio.known());
  // The next window starts known again.
  tick.promise_known = true;
  while (!windows.tick(0.01, tick, 8500.0, out)) {
  }
  EXPECT_TRUE(out.promise_known);
}

TEST(TrimmedDuty, ScalesTheNozzlesFlowNotItsDuty) {
  NozzleLine line;  // q = 0.00393 s + 0.217 at 0.4 MPa: a large intercept
  for (double duty : {25.0, 50.0, 75.0}) {
    const double trimmed = trimmed_duty_pct(line, duty, 1.1, 0.4);
    EXPECT_NEAR(flow_for_duty_l_per_min(line, trimmed, 0.4),
                1.1 * flow_for_duty_l_per_min(line, duty, 0.4), 1e-12)
        << duty;
    // Scaling the duty instead would move the flow by less than 10 % (the intercept).
    EXPECT_GT(trimmed, 1.1 * duty) << duty;
  }
  EXPECT_EQ(trimmed_duty_pct(line, 0.0, 1.2, 0.4), 0.0);      // closed stays closed
  EXPECT_EQ(trimmed_duty_pct(line, 100.0, 0.8, 0.4), 100.0);  // held open is not trimmed
  EXPECT_DOUBLE_EQ(trimmed_duty_pct(line, 40.0, 1.0, 0.4), 40.0);
}

TEST(PromisedFlow, ClosedHeldOpenOrTheLine) {
  NozzleLine line;
  line.full_open_flow_l_per_min = 0.7;
  EXPECT_EQ(promised_flow_l_per_min(line, 0.0, 0.4), 0.0);
  EXPECT_NEAR(promised_flow_l_per_min(line, 100.0, 0.4), 0.7, 1e-12);  // not the line at 100 %
  EXPECT_NEAR(promised_flow_l_per_min(line, 50.0, 0.4), flow_for_duty_l_per_min(line, 50.0, 0.4),
              1e-12);
}

// calibration_drift's measure: the meter over the lines' promise at the commanded duties,
// unknown (1) for its first 30 s of usable windows, volumes forgotten over 60 s; unlike FlowTrim it
// needs no modulated share (all nozzles held open still tells it the boom's state), and it
// skips windows whose flow, open valves or pressure make the promise meaningless.
TEST(CalibrationRatio, AveragesTheMeterOverThePromiseOnceItHasSeenEnough) {
  CalibrationRatio ratio(FlowTrimConfig{});
  FlowTrimInput w;
  w.requested_total_l_per_min = 2.0;  // promised at the commanded duties
  w.trimmable_l_per_min = 0.0;        // every nozzle held open
  w.measured_total_l_per_min = 2.16;
  w.open_fraction = 1.0;
  w.dt_s = 1.0;
  for (int s = 0; s < 29; ++s) ratio.update(w);
  EXPECT_FALSE(ratio.known());
  EXPECT_EQ(ratio.ratio(), 1.0);
  FlowTrimInput off_pressure = w;  // not counted: neither its ratio nor its time
  off_pressure.pressure_error_fraction = 0.2;
  off_pressure.measured_total_l_per_min = 4.0;
  ratio.update(off_pressure);
  FlowTrimInput closed = w;
  closed.open_fraction = 0.05;
  closed.measured_total_l_per_min = 4.0;
  ratio.update(closed);
  EXPECT_FALSE(ratio.known());
  ratio.update(w);
  ASSERT_TRUE(ratio.known());
  EXPECT_NEAR(ratio.ratio(), 1.08, 1e-9);
  // A change: the old volumes are forgotten with the 60 s time constant (equal promises, so
  // the ratio is the volumes' weighted mean).
  w.measured_total_l_per_min = 2.4;  // 1.2
  for (int s = 0; s < 300; ++s) ratio.update(w);
  EXPECT_NEAR(ratio.ratio(), 1.2, 0.12 * 0.01);
  EXPECT_LT(ratio.ratio(), 1.2);
  ratio.reset();
  EXPECT_FALSE(ratio.known());
  EXPECT_EQ(ratio.ratio(), 1.0);
  EXPECT_THROW(CalibrationRatio(FlowTrimConfig{}, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace weedspray::control
