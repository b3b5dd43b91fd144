// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <cmath>

#include "daemon/maps/density_grid.hpp"
#include "daemon/maps/stretches.hpp"
#include "tests/unit/daemon/local_metres.hpp"

namespace weedspray::daemon::maps {
namespace {

const LatLon kField{52.0, 5.0};
constexpr double kPeriod = 0.2;  // s between records
constexpr double kWidth = 0.5;

std::pair<double, double> metres(LatLon p) {
  return test::metres(kField, p);
}

// Two nozzles driving at `speed` along `heading`; nozzle 0 sprays with `duty` (0: closed) at
// 200 L/ha, nozzle 1 never. Its patch is at `along` metres from the field origin.
AsAppliedRow row(double along, double duty, double heading = 0, double speed = 1.0) {
  AsAppliedRow r;
  r.has_position = true;
  r.nozzles_placed = true;
  r.course_deg = heading;
  r.nozzle_width_m = kWidth;
  r.speed_m_per_s = speed;
  const double h = heading * M_PI / 180;
  r.antenna = step(kField, along * std::cos(h), along * std::sin(h));
  r.patch = {r.antenna, r.antenna};
  r.duty_pct = {duty, 0};
  r.density = {0.2, 0.0};
  r.crop_density = {0.1, 0.3};
  r.rate_l_per_ha = {duty > 0 ? 200.0 : 0.0, 0};
  r.nozzle_speed_m_per_s = {speed, speed};
  r.utc_ns = static_cast<std::int64_t>(along / speed * 1e9) + 1'000'000'000;
  return r;
}

struct Collect {
  std::vector<Stretch> stretches;
  StretchBuilder builder;
  explicit Collect(double max_length_m = 2.0)
      : builder(2, StretchOptions{max_length_m},
                [this](const Stretch& s) { stretches.push_back(s); }) {}
};

TEST(Stretches, ANozzleClosingEndsItsStretch) {
  Collect c;
  double along = 0;
  for (int i = 0; i < 5; ++i) c.builder.add(row(along += 0.2, 50), kPeriod);  // 1 m sprayed
  c.builder.add(row(along += 0.2, 0), kPeriod);                               // closed
  for (int i = 0; i < 3; ++i) c.builder.add(row(along += 0.2, 80), kPeriod);  // 0.6 m
  c.builder.end_all();
  ASSERT_EQ(c.stretches.size(), 2U) << "nozzle 1 never sprayed: no stretch of its own";
  const Stretch& a = c.stretches[0];
  const Stretch& b = c.stretches[1];
  EXPECT_EQ(a.nozzle, 0U);
  EXPECT_NEAR(a.length_m, 1.0, 1e-9);
  EXPECT_NEAR(a.area_m2, 1.0 * kWidth, 1e-9);
  EXPECT_NEAR(a.volume_l, 200.0 * a.area_m2 / 10000, 1e-12);
  EXPECT_NEAR(a.rate_l_per_ha(), 200.0, 1e-9);
  EXPECT_NEAR(a.mean(a.duty_pct_s), 50.0, 1e-9);
  EXPECT_NEAR(a.mean(a.weed_density_s), 0.2, 1e-9);
  EXPECT_NEAR(b.length_m, 0.6, 1e-9);
  EXPECT_NEAR(b.mean(b.duty_pct_s), 80.0, 1e-9);
  // The first record covered the 0.2 m behind its patch: the strip runs 0.0 .. 1.0 m north,
  // the second 1.2 .. 1.8 m (the closed record's 0.2 m is not in either).
  EXPECT_NEAR(metres(a.left.front()).first, 0.0, 1e-6);
  EXPECT_NEAR(metres(a.left.back()).first, 1.0, 1e-6);
  EXPECT_NEAR(metres(b.left.front()).first, 1.2, 1e-6);
  EXPECT_NEAR(metres(b.right.back()).first, 1.8, 1e-6);
  EXPECT_EQ(a.utc_start_ns, 1'000'000'000);
  EXPECT_EQ(a.utc_end_ns, 2'000'000'000);
}

TEST(Stretches, EdgesAreHalfAWidthEachSideAcrossTheHeading) {
  for (const double heading : {0.0, 90.0, 200.0}) {
    Collect c;
    c.builder.add(row(0.2, 50, heading), kPeriod);
    c.builder.add(row(0.4, 50, heading), kPeriod);
    c.builder.end_all();
    ASSERT_EQ(c.stretches.size(), 1U);
    const auto [ln, le] = metres(c.stretches[0].left.back());
    const auto [rn, re] = metres(c.stretches[0].right.back());
    EXPECT_NEAR(std::hypot(ln - rn, le - re), kWidth, 1e-6);
    // Left is 90 deg counter-clockwise of the heading: (north, east) = (-sin h, ... ) flipped.
    const double h = heading * M_PI / 180;
    const auto [pn, pe] = metres(step(kField, 0.4 * std::cos(h), 0.4 * std::sin(h)));
    EXPECT_NEAR(ln - pn, std::sin(h) * kWidth / 2, 1e-6) << heading;
    EXPECT_NEAR(le - pe, -std::cos(h) * kWidth / 2, 1e-6) << heading;
  }
}

TEST(Stretches, ALongStretchIsCutAtMaxLengthWithoutAGap) {
  Collect c(2.0);
  double along = 0;
  for (int i = 0; i < 15; ++i) c.builder.add(row(along += 0.2, 60), kPeriod);  // 3 m
  c.builder.end_all();
  ASSERT_EQ(c.stretches.size(), 2U);
  EXPECT_NEAR(c.stretches[0].length_m, 2.0, 1e-9);
  EXPECT_NEAR(c.stretches[1].length_m, 1.0, 1e-9);
  const auto [end_n, end_e] = metres(c.stretches[0].left.back());
  const auto [start_n, start_e] = metres(c.stretches[1].left.front());
  EXPECT_NEAR(end_n, start_n, 1e-9);
  EXPECT_NEAR(end_e, start_e, 1e-9);
  EXPECT_EQ(c.stretches[0].utc_end_ns, c.stretches[1].utc_start_ns);
  EXPECT_NEAR(c.stretches[0].area_m2 + c.stretches[1].area_m2, 3.0 * kWidth, 1e-9);
}

TEST(Stretches, NoStretchRunsPastMaxLength) {
  // 1.5 m/s, a record every 0.2 s: 0.3 m a record, 2 m is not a whole number of records.
  Collect c(2.0);
  double along = 0;
  for (int i = 0; i < 20; ++i) c.builder.add(row(along += 0.3, 60, 0, 1.5), kPeriod);  // 6 m
  c.builder.end_all();
  double total = 0;
  for (const Stretch& s : c.stretches) {
    EXPECT_LE(s.length_m, 2.0 + 1e-9);
    total += s.length_m;
  }
  EXPECT_EQ(c.stretches.size(), 4U);  // 1.8 + 1.8 + 1.8 + 0.6
  EXPECT_NEAR(total, 6.0, 1e-9);
}

TEST(Stretches, ALostFixEndsTheStretch) {
  Collect c;
  c.builder.add(row(0.2, 50), kPeriod);
  c.builder.add(row(0.4, 50), kPeriod);
  AsAppliedRow lost = row(0.6, 50);
  lost.has_position = false;
  lost.nozzles_placed = false;
  c.builder.add(lost, kPeriod);
  c.builder.add(row(0.8, 50), kPeriod);
  c.builder.add(row(1.0, 50), kPeriod);
  c.builder.end_all();
  ASSERT_EQ(c.stretches.size(), 2U);
  EXPECT_NEAR(c.stretches[0].length_m, 0.4, 1e-9);
  EXPECT_NEAR(c.stretches[1].length_m, 0.4, 1e-9);
}

TEST(Stretches, StandingStillSpraysNoArea) {
  Collect c;
  c.builder.add(row(0.2, 50, 0, 0.0), kPeriod);
  c.builder.add(row(0.2, 50, 0, 0.0), kPeriod);
  c.builder.end_all();
  ASSERT_EQ(c.stretches.size(), 1U);
  EXPECT_EQ(c.stretches[0].area_m2, 0.0);
  EXPECT_EQ(c.stretches[0].rate_l_per_ha(), 0.0);
}

TEST(DensityGrid, MeansPerCellAndSquareCells) {
  DensityGrid grid(2.0);
  grid.add(step(kField, 0.1, 0.1), 0.2, 0.4);
  grid.add(step(kField, 1.9, 1.5), 0.4, 0.0);
  grid.add(step(kField, 2.5, 0.1), 0.9, 0.1);   // the cell north of the first
  grid.add(step(kField, 0.1, -0.5), 0.0, 0.0);  // the cell west of the first
  const std::vector<DensityCell> cells = grid.cells();
  ASSERT_EQ(cells.size(), 3U);
  bool found = false;
  for (const DensityCell& c : cells) {
    const auto [sw_n, sw_e] = metres(c.corners[0]);
    const auto [ne_n, ne_e] = metres(c.corners[2]);
    EXPECT_NEAR(ne_n - sw_n, 2.0, 1e-6);
    EXPECT_NEAR(ne_e - sw_e, 2.0, 1e-6);
    if (std::abs(sw_n - 0.1) < 1e-6 && std::abs(sw_e - 0.1) < 1e-6) {
      found = true;
      EXPECT_EQ(c.samples, 2U);
      EXPECT_NEAR(c.weed_density, 0.3, 1e-9);
      EXPECT_NEAR(c.crop_density, 0.2, 1e-9);
    }
  }
  EXPECT_TRUE(found) << "the grid's origin is its first point: that cell's south-west corner";
}

}  // namespace
}  // namespace weedspray::daemon::maps
