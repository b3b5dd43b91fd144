// SPDX-License-Identifier: Apache-2.0
// weedspray-export-map over several boards' logs: two boards of one machine write their own
// as-applied logs (the same GNSS track, each with its own nozzles and antenna offset, their
// records interleaved in time), exported with two --dir into one map, read back as GeoJSON.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "daemon/maps/map_export.hpp"
#include "daemon/records/as_applied_log.hpp"
#include "tests/unit/daemon/local_metres.hpp"

namespace weedspray::daemon {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr LatLon kStart{52.0, 5.0};
constexpr int kRecords = 60;           // 0.2 s apart at 2 m/s north: 24 m
constexpr std::uint32_t kNozzles = 4;  // 0.5 m each: a board is 2 m of boom
const std::int64_t kUtc0 = *parse_utc("2026-06-24T14:30:00Z");

// One board's log: the machine drives north from kStart; the board's nozzles sit where its
// [gnss] antenna_right_of_centre_m puts them. `clock_s`: the board's own monotonic clock at the
// first record; `utc_shift_ms` shifts its records against the other board's (they interleave).
void write_board(const fs::path& dir, double antenna_right_of_centre_m, double clock_s,
                 int utc_shift_ms) {
  AsAppliedLog log(dir, 1 << 20, 5, NozzlePlacement{0.5, {0.0, antenna_right_of_centre_m}});
  for (int i = 0; i < kRecords; ++i) {
    AppliedRecord r;
    r.nozzles = kNozzles;
    const double t_s = 0.2 * i + utc_shift_ms / 1000.0;
    r.time = std::chrono::nanoseconds(static_cast<std::int64_t>((clock_s + t_s) * 1e9));
    r.speed_m_per_s = 2.0;
    for (std::uint32_t n = 0; n < kNozzles; ++n) {
      // Nozzle 1 closes now and then: stretches of several lengths.
      r.duty_pct[n] = n == 1 && i % 7 == 3 ? 0.0f : 50.0f;
      r.density[n] = 0.1f * static_cast<float>(n);
      r.crop_density[n] = 0.05f;
      r.nozzle_speed_m_per_s[n] = 2.0f;
      r.nozzle_flow_l_per_min[n] = r.duty_pct[n] > 0 ? 0.6f : 0.0f;
    }
    r.fix.mode = io::GnssFixMode::k3D;
    const LatLon at = step(kStart, 2.0 * t_s, 0.0);
    r.fix.latitude_deg = at.latitude_deg;
    r.fix.longitude_deg = at.longitude_deg;
    r.fix.speed_m_per_s = 2.0;
    r.fix.course_deg = 0;
    r.fix.utc_ns = kUtc0 + static_cast<std::int64_t>(t_s * 1e9);
    r.fix_time = r.time;
    r.fix_usable = true;
    ASSERT_TRUE(log.write(r));
  }
  log.flush();
}

json read_json(const fs::path& file) {
  std::ifstream in(file);
  return json::parse(in);
}

class MapExportMerge : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ =
        fs::temp_directory_path() /
        ("weedspray-merge-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    // Antenna at the machine's centre: 1 m right of the left board's centre, 1 m left of the
    // right board's.
    write_board(root_ / "left", 1.0, 100.0, 0);
    // The right board's clock runs on from the left's last record (0.2 s later), so reading
    // the two as one log would join their stretches.
    write_board(root_ / "right", -1.0, 100.0 + 0.2 * kRecords - 0.3, 100);
  }
  void TearDown() override { fs::remove_all(root_); }

  // Runs the built weedspray-export-map (as sprayctl export-map does) to a GeoJSON folder.
  json sprayed(const std::vector<std::string>& boards, const std::string& out) {
    std::string command = std::string(WEEDSPRAY_EXPORT_MAP) + " --format geojson";
    for (const std::string& b : boards) command += " --dir " + (root_ / b).string();
    command += " " + (root_ / out).string() + " >/dev/null";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    last_out_ = root_ / out;
    return read_json(root_ / out / "sprayed.geojson")["features"];
  }

  fs::path root_, last_out_;
};

// The east offset of a feature's vertices from the track: the range they span.
std::pair<double, double> east_span(const json& feature) {
  double low = 1e9, high = -1e9;
  for (const json& point : feature["geometry"]["coordinates"][0]) {
    const auto [n, e] = test::metres(kStart, {point[1].get<double>(), point[0].get<double>()});
    low = std::min(low, e);
    high = std::max(high, e);
  }
  return {low, high};
}

TEST_F(MapExportMerge, TwoBoardsMakeOneMapOfBothSideBySide) {
  const json left = sprayed({"left"}, "left-map");
  const json right = sprayed({"right"}, "right-map");
  const json both = sprayed({"left", "right"}, "both-map");
  const json grid = read_json(last_out_ / "weed_density.geojson")["features"];
  ASSERT_GT(left.size(), 0U);
  ASSERT_GT(right.size(), 0U);
  // One folder: the map as before, without a board field.
  for (const json& f : left) EXPECT_FALSE(f["properties"].contains("board"));
  EXPECT_EQ(left[0]["properties"].size(), 10U);

  // The union of both boards' stretches, each named by its folder and equal to its board's
  // own export: no stretch lost, split or joined across boards.
  ASSERT_EQ(both.size(), left.size() + right.size());
  json from_left = json::array(), from_right = json::array();
  for (json f : both) {
    ASSERT_TRUE(f["properties"].contains("board"));
    const std::string board = f["properties"]["board"];
    f["properties"].erase("board");
    (board == "left" ? from_left : from_right).push_back(f);
    ASSERT_TRUE(board == "left" || board == "right") << board;
  }
  EXPECT_TRUE(from_left == left) << from_left.size() << " of the left board's " << left.size();
  EXPECT_TRUE(from_right == right) << from_right.size() << " of the right board's " << right.size();

  // Each board's patches on its own side of the track (its own antenna offset), side by side:
  // a stretch joining two boards' records would span both sides.
  for (const json& f : both) {
    const auto [low, high] = east_span(f);
    if (f["properties"]["board"] == "left") {
      EXPECT_GE(low, -2.0 - 1e-3);
      EXPECT_LE(high, 0.0 + 1e-3);
    } else {
      EXPECT_GE(low, 0.0 - 1e-3);
      EXPECT_LE(high, 2.0 + 1e-3);
    }
  }

  // One grid over both: every nozzle record of either board is a sample.
  std::int64_t samples = 0;
  for (const json& cell : grid) samples += cell["properties"]["samples"].get<std::int64_t>();
  EXPECT_EQ(samples, 2 * kRecords * static_cast<std::int64_t>(kNozzles));
}

TEST(MapExportBoards, NamedByTheirFoldersOrAsManyPartsAsTellThemApart) {
  EXPECT_EQ(maps::board_names({"/x/left", "/x/right/"}),
            (std::vector<std::string>{"left", "right"}));
  EXPECT_EQ(maps::board_names({"/a/left/as-applied", "/a/right/as-applied/."}),
            (std::vector<std::string>{"left/as-applied", "right/as-applied"}));
  EXPECT_THROW(maps::board_names({"/x/left", "/x/./left/"}), std::runtime_error);
}

}  // namespace
}  // namespace weedspray::daemon
