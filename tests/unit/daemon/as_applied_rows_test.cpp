// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/as_applied_rows.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "daemon/records/as_applied_log.hpp"
#include "daemon/records/as_applied_reader.hpp"
#include "tests/unit/daemon/local_metres.hpp"

namespace weedspray::daemon {
namespace {

namespace fs = std::filesystem;

class AsAppliedRowsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("weedspray-rows-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

using test::metres;

TEST_F(AsAppliedRowsTest, PositionsUtcAndRatesRoundTripThroughTheLog) {
  const LatLon fix_at{52.0, 5.0};
  fs::path file;
  {
    // Antenna 1 m ahead of the nozzle line, on the centre line; 2 nozzles 0.5 m apart.
    AsAppliedLog log(dir_, 1 << 20, 5, NozzlePlacement{0.5, {1.0, 0.0}});
    AppliedRecord r;
    r.nozzles = 2;
    r.time = std::chrono::milliseconds(10'300);
    r.speed_m_per_s = 2.0;
    r.duty_pct = {60, 0};
    r.density = {0.25f, 0.0f};
    r.crop_density = {0.5f, 0.125f};
    r.nozzle_speed_m_per_s = {2.0f, 2.0f};
    r.nozzle_flow_l_per_min = {1.2f, 0.0f};
    r.fix.mode = io::GnssFixMode::k3D;
    r.fix.latitude_deg = fix_at.latitude_deg;
    r.fix.longitude_deg = fix_at.longitude_deg;
    r.fix.speed_m_per_s = 2.0;
    r.fix.course_deg = 90;  // east
    r.fix.utc_ns = *parse_utc("2026-06-24T14:30:00.000Z");
    r.fix_time = std::chrono::milliseconds(10'050);  // 0.25 s before the record
    r.fix_usable = true;
    ASSERT_TRUE(log.write(r));
    r.fix_usable = false;  // the fix went stale: no position, no UTC
    r.time += std::chrono::milliseconds(200);
    ASSERT_TRUE(log.write(r));
    log.flush();
    file = log.current_file();
  }
  AsAppliedRows rows(file);
  ASSERT_TRUE(rows.has_map_columns());
  ASSERT_EQ(rows.nozzles(), 2U);
  AsAppliedRow row;
  ASSERT_TRUE(rows.next(row));
  EXPECT_EQ(format_utc_ms(row.utc_ns), "2026-06-24T14:30:00.250Z");
  ASSERT_TRUE(row.has_position);
  ASSERT_TRUE(row.nozzles_placed);
  // 0.25 s at 2 m/s east: the antenna 0.5 m east of the fix.
  auto [n, e] = metres(fix_at, row.antenna);
  EXPECT_NEAR(n, 0.0, 0.002);
  EXPECT_NEAR(e, 0.5, 0.002);
  // Nozzle 0 (left, looking east: north) 0.25 m north, 1 m behind (west of) the antenna.
  std::tie(n, e) = metres(fix_at, row.patch[0]);
  EXPECT_NEAR(n, 0.25, 0.002);
  EXPECT_NEAR(e, -0.5, 0.002);
  std::tie(n, e) = metres(fix_at, row.patch[1]);
  EXPECT_NEAR(n, -0.25, 0.002);
  EXPECT_NEAR(row.course_deg, 90.0, 1e-9);
  EXPECT_NEAR(row.nozzle_width_m, 0.5, 1e-9);
  EXPECT_NEAR(row.rate_l_per_ha[0], 200.0, 0.05);
  EXPECT_EQ(row.rate_l_per_ha[1], 0.0);
  EXPECT_NEAR(row.duty_pct[0], 60.0, 1e-9);
  EXPECT_NEAR(row.density[0], 0.25, 1e-9);
  EXPECT_NEAR(row.crop_density[1], 0.125, 1e-9);
  ASSERT_TRUE(rows.next(row));
  EXPECT_FALSE(row.has_position);
  EXPECT_FALSE(row.nozzles_placed);
  EXPECT_EQ(row.utc_ns, 0);
  EXPECT_FALSE(rows.next(row));
  // The summing reader still reads the longer lines.
  EXPECT_EQ(read_as_applied_file(file).records, 2U);
}

TEST_F(AsAppliedRowsTest, FilesOfTheFirstFormatReadWithoutPositions) {
  fs::create_directories(dir_);
  const fs::path file = dir_ / "as-applied-20260101T000000Z-000.csv";
  std::ofstream(file) << "time_s,distance_m,speed_m_per_s,pressure_mpa,flow_l_per_min,volume_l,"
                         "duty_pct_0,duty_pct_1,density_0,density_1,crop_density_0,"
                         "crop_density_1\n"
                         "1.0000,0.5000,1.000,0.3000,1.2000,0.0040000,50.0,0.0,0.2000,0.0000,"
                         "0.1000,0.0000\n"
                         "1.2000,0.7000,1.0";  // torn
  AsAppliedRows rows(file);
  EXPECT_FALSE(rows.has_map_columns());
  AsAppliedRow row;
  ASSERT_TRUE(rows.next(row));
  EXPECT_FALSE(row.has_position);
  EXPECT_NEAR(row.duty_pct[0], 50.0, 1e-9);
  EXPECT_FALSE(rows.next(row));
  EXPECT_EQ(rows.torn_tail_lines(), 1U);
  EXPECT_EQ(rows.damaged_lines(), 0U);
}

TEST_F(AsAppliedRowsTest, NotAnAsAppliedFileIsAnErrorNamingIt) {
  fs::create_directories(dir_);
  const fs::path file = dir_ / "other.csv";
  std::ofstream(file) << "a,b\n1,2\n";
  try {
    AsAppliedRows rows(file);
    FAIL() << "accepted " << file;
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(file.string()), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace weedspray::daemon
