// SPDX-License-Identifier: Apache-2.0
#include "control/nozzle_scheduler.hpp"

#include "control/odometry.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace weedspray::control {
namespace {

// A camera 1 m up whose image covers the ground 1 m to 3 m ahead (UGV paper's layout).
CameraGeometry one_to_three_metres() {
  const double bottom = std::atan(1.0), top = std::atan(3.0);
  CameraGeometry g;
  g.mount_height_m = 1.0;
  g.tilt_from_vertical_rad = 0.5 * (bottom + top);
  g.vertical_fov_rad = top - bottom;
  g.camera_to_nozzle_m = 1.2;
  return g;
}

TEST(CameraFootprint, NadirCamera) {
  CameraGeometry g;
  g.mount_height_m = 2.0;
  g.tilt_from_vertical_rad = 0.0;
  g.vertical_fov_rad = 2.0 * std::atan(0.25);
  const GroundInterval f = ground_footprint(g);
  EXPECT_NEAR(f.near_m, -0.5, 1e-12);
  EXPECT_NEAR(f.far_m, 0.5, 1e-12);
  // Image centre row looks straight down.
  EXPECT_NEAR(ground_distance_of_row(g, 0.5), 0.0, 1e-12);
}

TEST(CameraFootprint, TiltedCamera) {
  const GroundInterval f = ground_footprint(one_to_three_metres());
  EXPECT_NEAR(f.near_m, 1.0, 1e-12);
  EXPECT_NEAR(f.far_m, 3.0, 1e-12);
}

TEST(CameraFootprint, ZoneRowsTileTheFootprintTopIsFar) {
  const CameraGeometry g = one_to_three_metres();
  const GroundInterval top = zone_ground_interval(g, 2, 0);
  const GroundInterval bottom = zone_ground_interval(g, 2, 1);
  EXPECT_NEAR(top.far_m, 3.0, 1e-12);
  EXPECT_NEAR(bottom.near_m, 1.0, 1e-12);
  EXPECT_NEAR(top.near_m, bottom.far_m, 1e-12);
  // Perspective: the upper half of the image covers more ground than the lower half.
  EXPECT_GT(top.far_m - top.near_m, bottom.far_m - bottom.near_m);
  // The middle row's ray is the optical axis: h tan(tilt).
  EXPECT_NEAR(top.near_m, std::tan(g.tilt_from_vertical_rad), 1e-12);
}

TEST(CameraFootprint, RejectsAHorizonInTheImage) {
  CameraGeometry g = one_to_three_metres();
  g.tilt_from_vertical_rad = 1.4;
  EXPECT_THROW(validate(g), std::invalid_argument);
  g = one_to_three_metres();
  g.mount_height_m = 0.0;
  EXPECT_THROW(validate(g), std::invalid_argument);
  NozzleSchedulerConfig config;
  config.rows = 0;
  EXPECT_THROW(NozzleScheduler{config}, std::invalid_argument);
}

struct Interval {
  double start, end;
};

// Speed varies 0.5 .. 1.5 m/s; frames are taken every 2 m so their footprints tile the
// ground; the valves have 50 ms opening and 30 ms closing delays. The simulated valve sprays
// ground intervals that must match the imaged zone intervals within 1 cm.
TEST(NozzleScheduler, SprayedGroundMatchesImagedZonesAtVaryingSpeed) {
  NozzleSchedulerConfig config;
  config.geometry = one_to_three_metres();
  config.nozzles = 4;
  config.rows = 2;
  config.opening_delay_s = 0.05;
  config.closing_delay_s = 0.03;
  NozzleScheduler scheduler(config);
  const double c2n = config.geometry.camera_to_nozzle_m;

  auto speed = [](double t) { return 1.0 + 0.5 * std::sin(0.7 * t); };
  auto odometer = [](double t) { return t + 0.5 / 0.7 * (1.0 - std::cos(0.7 * t)); };
  auto decision = [](int frame, std::size_t row, std::size_t nozzle) {
    const unsigned h =
        static_cast<unsigned>(frame * 7 + static_cast<int>(row) * 3 + static_cast<int>(nozzle) * 5);
    return (h * 2654435761u >> 13) % 3 == 0 ? 0.0 : 60.0;
  };

  // Expected sprayed ground per nozzle: merged runs of zones with a duty.
  constexpr int kFrames = 12;
  std::vector<std::vector<Interval>> expected(config.nozzles);
  for (std::size_t n = 0; n < config.nozzles; ++n) {
    for (int k = 0; k < kFrames; ++k) {
      for (std::size_t row : {std::size_t{1}, std::size_t{0}}) {  // near row first on the ground
        if (decision(k, row, n) <= 0.0) continue;
        const GroundInterval zone = scheduler.row_intervals()[row];
        const Interval ground{2.0 * k + zone.near_m, 2.0 * k + zone.far_m};
        if (!expected[n].empty() && std::abs(expected[n].back().end - ground.start) < 1e-9) {
          expected[n].back().end = ground.end;
        } else {
          expected[n].push_back(ground);
        }
      }
    }
  }

  // Simulate: 0.25 ms control steps; the valve follows its command after the delays.
  const double dt = 0.00025;
  std::vector<std::vector<Interval>> sprayed(config.nozzles);
  std::vector<bool> command(config.nozzles, false);
  std::vector<double> pending_change_time(config.nozzles, -1.0);
  std::vector<bool> physical(config.nozzles, false);
  int next_frame = 0;
  for (double t = 0.0; odometer(t) < 2.0 * kFrames + 1.5 + c2n; t += dt) {
    const double d = odometer(t), v = speed(t);
    while (next_frame < kFrames && d >= 2.0 * next_frame) {
      std::vector<double> duties(config.rows * config.nozzles);
      for (std::size_t r = 0; r < config.rows; ++r) {
        for (std::size_t n = 0; n < config.nozzles; ++n) {
          duties[r * config.nozzles + n] = decision(next_frame, r, n);
        }
      }
      ASSERT_TRUE(scheduler.add_frame(2.0 * next_frame, duties));
      ++next_frame;
    }
    for (std::size_t n = 0; n < config.nozzles; ++n) {
      const double duty = scheduler.duty_at(n, d, v);
      const bool on = duty > 0.0;
      if (on) {
        EXPECT_DOUBLE_EQ(duty, 60.0);
      }
      if (on != command[n]) {
        command[n] = on;
        pending_change_time[n] = t + (on ? config.opening_delay_s : config.closing_delay_s);
      }
      if (pending_change_time[n] >= 0.0 && t >= pending_change_time[n]) {
        // Interpolate the nozzle's ground position at the exact physical change time.
        const double x = odometer(pending_change_time[n]) - c2n;
        if (command[n] && !physical[n]) sprayed[n].push_back({x, x});
        if (!command[n] && physical[n]) sprayed[n].back().end = x;
        physical[n] = command[n];
        pending_change_time[n] = -1.0;
      }
    }
  }
  for (std::size_t n = 0; n < config.nozzles; ++n) {
    ASSERT_EQ(sprayed[n].size(), expected[n].size()) << "nozzle " << n;
    for (std::size_t i = 0; i < expected[n].size(); ++i) {
      EXPECT_NEAR(sprayed[n][i].start, expected[n][i].start, 0.01) << "nozzle " << n << " #" << i;
      EXPECT_NEAR(sprayed[n][i].end, expected[n][i].end, 0.01) << "nozzle " << n << " #" << i;
    }
  }
}

// The full chain as the daemon runs it: wheel pulses -> Odometry; frames every 1.5 s (time
// based, so footprints overlap or leave gaps as the speed varies) registered 120 ms late with
// the odometer reading interpolated at the frame's timestamp; newest decision wins. The ground
// the simulated valve sprays must differ from the newest-wins imaged plan only within 1 cm of
// the plan's on/off boundaries.
TEST(NozzleScheduler, OdometryInTheLoopMatchesThePlanWithinOneCentimetre) {
  using std::chrono::nanoseconds;
  NozzleSchedulerConfig config;
  config.geometry = one_to_three_metres();
  config.nozzles = 2;
  config.rows = 2;
  config.opening_delay_s = 0.04;
  config.closing_delay_s = 0.025;
  NozzleScheduler scheduler(config);
  const double c2n = config.geometry.camera_to_nozzle_m;
  OdometryConfig odo_config;
  odo_config.pulses_per_metre = 500.0;
  Odometry odometry(odo_config);

  // True speed 1 + 0.5 sin(0.9 t + 0.3) m/s, integrated:
  auto odometer = [](double t) {
    return t + 0.5 / 0.9 * (std::cos(0.3) - std::cos(0.9 * t + 0.3));
  };
  auto decision = [](int frame, std::size_t row, std::size_t nozzle) {
    const unsigned h = static_cast<unsigned>(frame * 11 + static_cast<int>(row) * 5 +
                                             static_cast<int>(nozzle) * 3 + 1);
    return (h * 2654435761u >> 11) % 2 == 0 ? 0.0 : 45.0;
  };
  auto to_ns = [](double t) { return nanoseconds(static_cast<long long>(std::llround(t * 1e9))); };

  constexpr int kFrames = 14;
  const double frame_period = 1.5, frame_latency = 0.12;
  // Expected plan on a 1 mm ground grid: the newest frame covering x decides.
  const double grid = 0.001;
  const double x_end = odometer(0.3 + frame_period * (kFrames - 1)) + 3.0;
  const std::size_t cells = static_cast<std::size_t>(x_end / grid) + 1;
  std::vector<std::vector<int>> plan(config.nozzles, std::vector<int>(cells, 0));
  for (int k = 0; k < kFrames; ++k) {
    const double d_frame = odometer(0.3 + frame_period * k);
    for (std::size_t r = 0; r < config.rows; ++r) {
      const GroundInterval zone = scheduler.row_intervals()[r];
      for (std::size_t n = 0; n < config.nozzles; ++n) {
        for (std::size_t c = 0; c < cells; ++c) {
          const double x = (static_cast<double>(c) + 0.5) * grid;
          if (x >= d_frame + zone.near_m && x < d_frame + zone.far_m) {
            plan[n][c] = decision(k, r, n) > 0.0 ? 1 : 0;
          }
        }
      }
    }
  }

  std::vector<std::vector<Interval>> sprayed(config.nozzles);
  std::vector<bool> command(config.nozzles, false), physical(config.nozzles, false);
  std::vector<double> pending(config.nozzles, -1.0);
  std::uint64_t count = 0;
  nanoseconds last_edge{0};
  int next_frame = 0;
  const double dt = 0.00025;
  odometry.update(0, nanoseconds(0), nanoseconds(0));
  for (int step = 1; odometer(step * dt) < x_end + c2n; ++step) {
    const double t = step * dt;
    // Wheel edges: each crossing of a pulse boundary, timed exactly by bisection.
    while (std::floor(odometer(t) * odo_config.pulses_per_metre) > static_cast<double>(count)) {
      ++count;
      const double target = static_cast<double>(count) / odo_config.pulses_per_metre;
      double lo = t - dt, hi = t;
      for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        (odometer(mid) < target ? lo : hi) = mid;
      }
      last_edge = to_ns(hi);
    }
    if (step % 4 != 0) continue;  // 1 kHz control cycle
    const nanoseconds now = to_ns(t);
    odometry.update(count, last_edge, now);
    while (next_frame < kFrames && t >= 0.3 + frame_period * next_frame + frame_latency) {
      std::vector<double> duties(config.rows * config.nozzles);
      for (std::size_t r = 0; r < config.rows; ++r) {
        for (std::size_t n = 0; n < config.nozzles; ++n) {
          duties[r * config.nozzles + n] = decision(next_frame, r, n);
        }
      }
      const double d_frame = odometry.distance_at(to_ns(0.3 + frame_period * next_frame));
      ASSERT_TRUE(scheduler.add_frame(d_frame, duties));
      ++next_frame;
    }
    const double d = odometry.distance_at(now), v = odometry.speed_m_per_s();
    for (std::size_t n = 0; n < config.nozzles; ++n) {
      const bool on = scheduler.duty_at(n, d, v) > 0.0;
      if (on != command[n]) {
        command[n] = on;
        pending[n] = t + (on ? config.opening_delay_s : config.closing_delay_s);
      }
      if (pending[n] >= 0.0 && t >= pending[n]) {
        const double x = odometer(pending[n]) - c2n;
        if (command[n] && !physical[n]) sprayed[n].push_back({x, x_end});
        if (!command[n] && physical[n]) sprayed[n].back().end = x;
        physical[n] = command[n];
        pending[n] = -1.0;
      }
    }
  }

  for (std::size_t n = 0; n < config.nozzles; ++n) {
    std::vector<double> boundaries;
    for (std::size_t c = 1; c < cells; ++c) {
      if (plan[n][c] != plan[n][c - 1]) boundaries.push_back(static_cast<double>(c) * grid);
    }
    ASSERT_GT(boundaries.size(), 6u);  // the pattern really switches
    double worst = 0.0;
    std::size_t mismatched_cells = 0;
    for (std::size_t c = 0; c < cells; ++c) {
      const double x = (static_cast<double>(c) + 0.5) * grid;
      bool on = false;
      for (const Interval& i : sprayed[n]) on = on || (x >= i.start && x < i.end);
      if (on == (plan[n][c] != 0)) continue;
      ++mismatched_cells;
      double nearest = 1e9;
      for (double b : boundaries) nearest = std::min(nearest, std::abs(x - b));
      worst = std::max(worst, nearest);
    }
    EXPECT_LT(worst, 0.01) << "nozzle " << n << ": sprayed ground differs from the plan " << worst
                           << " m away from a boundary";
    RecordProperty("worst_boundary_error_m_nozzle_" + std::to_string(n), std::to_string(worst));
    (void)mismatched_cells;
  }
}

TEST(NozzleScheduler, NewestIntervalWinsWhereTheyOverlap) {
  NozzleSchedulerConfig config;
  config.nozzles = 1;
  config.opening_delay_s = 0.0;
  config.closing_delay_s = 0.0;
  config.geometry.camera_to_nozzle_m = 1.0;
  NozzleScheduler scheduler(config);
  scheduler.add_interval(0, 0.0, 2.0, 40.0);
  scheduler.add_interval(0, 1.0, 3.0, 80.0);
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 1.5, 0.0), 40.0);  // ground 0.5
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 2.5, 0.0), 80.0);  // ground 1.5: the newer one
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 4.5, 0.0), 0.0);   // ground 3.5: gap -> closed
  scheduler.add_interval(0, 0.5, 1.2, 0.0);                // a newer "no weeds" decision
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 2.0, 0.0), 0.0);
  scheduler.clear();
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 1.5, 0.0), 0.0);
}

TEST(NozzleScheduler, OpeningLeadScalesWithSpeed) {
  NozzleSchedulerConfig config;
  config.nozzles = 1;
  config.opening_delay_s = 0.1;
  config.closing_delay_s = 0.05;
  config.geometry.camera_to_nozzle_m = 0.0;
  NozzleScheduler scheduler(config);
  scheduler.add_interval(0, 10.0, 11.0, 100.0);
  // At 2 m/s the valve is commanded 0.2 m early and closed 0.1 m early.
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 9.79, 2.0), 0.0);
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 9.81, 2.0), 100.0);
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 10.89, 2.0), 100.0);
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 10.91, 2.0), 0.0);
  // Standing still: exactly the interval.
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 9.99, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 10.0, 0.0), 100.0);
}

TEST(NozzleScheduler, SlowerClosingEndsTheSprayByTheClosingLead) {
  NozzleSchedulerConfig config;
  config.nozzles = 1;
  config.opening_delay_s = 0.05;
  config.closing_delay_s = 0.1;  // solenoid valves usually close slower than they open
  config.geometry.camera_to_nozzle_m = 0.0;
  NozzleScheduler scheduler(config);
  scheduler.add_interval(0, 10.0, 11.0, 100.0);
  // At 2 m/s: opened 0.1 m early (not 0.2 m, which the closing point would suggest) ...
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 9.85, 2.0), 0.0);
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 9.91, 2.0), 100.0);
  // ... and closed 0.2 m early (not 0.1 m, which the opening point would suggest).
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 10.79, 2.0), 100.0);
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 10.85, 2.0), 0.0);
}

TEST(NozzleScheduler, HoldLastGapPolicy) {
  NozzleSchedulerConfig config;
  config.nozzles = 1;
  config.opening_delay_s = 0.0;
  config.closing_delay_s = 0.0;
  config.geometry.camera_to_nozzle_m = 0.0;
  config.gap_policy = GapPolicy::kHoldLast;
  config.hold_last_max_m = 0.5;
  NozzleScheduler scheduler(config);
  scheduler.add_interval(0, 0.0, 1.0, 70.0);
  scheduler.add_interval(0, 2.0, 3.0, 30.0);
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 1.3, 0.0), 70.0);  // held
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 1.7, 0.0), 0.0);   // beyond hold_last_max
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 2.1, 0.0), 30.0);
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, -0.5, 0.0), 0.0);  // nothing before
}

TEST(NozzleScheduler, RingOverwritesTheOldest) {
  NozzleSchedulerConfig config;
  config.nozzles = 2;
  config.plan_capacity = 4;
  config.opening_delay_s = 0.0;
  config.closing_delay_s = 0.0;
  config.geometry.camera_to_nozzle_m = 0.0;
  NozzleScheduler scheduler(config);
  for (int i = 0; i < 6; ++i) scheduler.add_interval(1, i, i + 1.0, 10.0 * (i + 1));
  EXPECT_DOUBLE_EQ(scheduler.duty_at(1, 0.5, 0.0), 0.0);  // overwritten
  EXPECT_DOUBLE_EQ(scheduler.duty_at(1, 1.5, 0.0), 0.0);  // overwritten
  EXPECT_DOUBLE_EQ(scheduler.duty_at(1, 2.5, 0.0), 30.0);
  EXPECT_DOUBLE_EQ(scheduler.duty_at(1, 5.5, 0.0), 60.0);
  EXPECT_DOUBLE_EQ(scheduler.duty_at(0, 5.5, 0.0), 0.0);                 // other nozzle untouched
  EXPECT_FALSE(scheduler.add_frame(0.0, std::vector<double>(3, 50.0)));  // wrong size
}

}  // namespace
}  // namespace weedspray::control
