// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/map_geometry.hpp"

#include <gtest/gtest.h>
#include "tests/unit/daemon/local_metres.hpp"

namespace weedspray::daemon {
namespace {

using test::metres;

const LatLon kField{52.0, 5.0};

TEST(MapGeometry, StepAndLocalOffsetAreInverse) {
  const LatLon p = step(kField, 3.0, -4.0);
  const auto [n, e] = metres(kField, p);
  EXPECT_NEAR(n, 3.0, 1e-9);
  EXPECT_NEAR(e, -4.0, 1e-9);
  // One metre north is 1/111195 of a degree of latitude on the mean sphere.
  EXPECT_NEAR(step(kField, 1.0, 0).latitude_deg - 52.0, 1.0 / 111195.08, 1e-10);
}

TEST(MapGeometry, AntennaCarriedAlongCourseAndSpeed) {
  io::GnssFix fix;
  fix.mode = io::GnssFixMode::k3D;
  fix.latitude_deg = kField.latitude_deg;
  fix.longitude_deg = kField.longitude_deg;
  fix.speed_m_per_s = 2.0;
  fix.course_deg = 180;  // south
  const auto [n, e] = metres(kField, *antenna_at(fix, 0.5));
  EXPECT_NEAR(n, -1.0, 1e-9);
  EXPECT_NEAR(e, 0.0, 1e-9);
  fix.course_deg = io::GnssFix::kUnknown;  // no course: stays where the fix was
  const auto [n2, e2] = metres(kField, *antenna_at(fix, 0.5));
  EXPECT_EQ(n2, 0.0);
  EXPECT_EQ(e2, 0.0);
  fix.mode = io::GnssFixMode::kNone;
  EXPECT_FALSE(antenna_at(fix, 0.5).has_value());
}

TEST(MapGeometry, NozzlePatchIsBehindAndBesideTheAntennaTurnedByHeading) {
  // Antenna 2 m ahead of the nozzle line and 0.3 m right of the boom's centre.
  const AntennaMount mount{2.0, 0.3};
  // Heading north: the leftmost of 4 nozzles 0.5 m apart (-0.75 m) is 1.05 m west of the
  // antenna, 2 m south of it.
  auto [n, e] = metres(kField, nozzle_patch(kField, 0, mount, -0.75));
  EXPECT_NEAR(n, -2.0, 1e-9);
  EXPECT_NEAR(e, -1.05, 1e-9);
  // Heading east: behind is west, left is north.
  std::tie(n, e) = metres(kField, nozzle_patch(kField, 90, mount, -0.75));
  EXPECT_NEAR(n, 1.05, 1e-9);
  EXPECT_NEAR(e, -2.0, 1e-9);
  // Heading south-west (225 deg): the rightmost nozzle (+0.75) is north-west of the centre.
  std::tie(n, e) = metres(kField, nozzle_patch(kField, 225, AntennaMount{}, 0.75));
  EXPECT_NEAR(n, 0.75 * std::sqrt(0.5), 1e-9);
  EXPECT_NEAR(e, -0.75 * std::sqrt(0.5), 1e-9);
}

TEST(MapGeometry, RatePerHectare) {
  // 1.2 L/min on a 0.5 m strip at 2 m/s: 0.02 L/s over 1 m2/s = 200 L/ha.
  EXPECT_NEAR(rate_l_per_ha(1.2, 2.0, 0.5), 200.0, 1e-9);
  EXPECT_NEAR(rate_l_per_ha(1.2, 1.0, 0.5), 400.0, 1e-9);
  EXPECT_EQ(rate_l_per_ha(0.0, 2.0, 0.5), 0.0);  // closed
  EXPECT_EQ(rate_l_per_ha(1.2, 0.0, 0.5), 0.0);  // standing
}

TEST(MapGeometry, UtcTextRoundTrip) {
  const std::int64_t t = *parse_utc("2026-06-24T14:30:01.250Z");
  EXPECT_EQ(format_utc_ms(t), "2026-06-24T14:30:01.250Z");
  EXPECT_EQ(format_utc_ms(t + 999'999), "2026-06-24T14:30:01.250Z");  // truncated to the ms
  EXPECT_EQ(*parse_utc("2026-06-24") + 14 * 3600'000'000'000LL + 30 * 60'000'000'000LL,
            *parse_utc("2026-06-24T14:30Z"));
  EXPECT_EQ(*parse_utc("2026-06-24T14:30:01"), t - 250'000'000);
  EXPECT_EQ(*parse_utc("1970-01-01T00:00:01Z"), 1'000'000'000);
  for (const char* bad : {"", "2026-6-24", "2026-06-24 14:30", "2026-06-24T14:30:01.x",
                          "2026-13-01", "2026-06-24T14:30+02:00"}) {
    EXPECT_FALSE(parse_utc(bad).has_value()) << bad;
  }
}

}  // namespace
}  // namespace weedspray::daemon
