// SPDX-License-Identifier: Apache-2.0
// Totals across restarts and the as-applied CSV log.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "daemon/records/as_applied_log.hpp"
#include "daemon/records/totals.hpp"

namespace weedspray::daemon {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("weedspray-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(Totals, SaveAndRestore) {
  const fs::path dir = temp_dir("totals");
  const fs::path file = dir / "totals.toml";
  EXPECT_EQ(load_totals(file).area_m2, 0.0);  // missing: zeros
  save_totals(file,
              Totals{.area_m2 = 1234.5, .volume_l = 10.25, .uniform_volume_l = 20.5, .log = {}});
  const Totals back = load_totals(file);
  EXPECT_DOUBLE_EQ(back.area_m2, 1234.5);
  EXPECT_DOUBLE_EQ(back.volume_l, 10.25);
  EXPECT_DOUBLE_EQ(back.savings_pct(), 50.0);
  EXPECT_FALSE(fs::exists(dir / "totals.toml.tmp"));
  fs::remove_all(dir);
}

TEST(Totals, TheLogMarkIsSavedAndRestored) {
  const fs::path dir = temp_dir("totals-mark");
  const fs::path file = dir / "totals.toml";
  save_totals(file, Totals{.area_m2 = 0,
                           .volume_l = 3,
                           .uniform_volume_l = 0,
                           .log = {.known = true, .seq = 12345678901, .queued_l = 0.125}});
  const Totals back = load_totals(file);
  EXPECT_TRUE(back.log.known);
  EXPECT_EQ(back.log.seq, 12345678901U);
  EXPECT_DOUBLE_EQ(back.log.queued_l, 0.125);
  std::ofstream(file) << "volume_l = 2.0\n";  // saved without a mark
  EXPECT_FALSE(load_totals(file).log.known);
  fs::remove_all(dir);
}

TEST(Totals, CorruptFileGivesZerosAndAnError) {
  const fs::path dir = temp_dir("totals-bad");
  std::ofstream(dir / "totals.toml") << "area_m2 = = 3\n";
  std::string error;
  const Totals t = load_totals(dir / "totals.toml", &error);
  EXPECT_EQ(t.area_m2, 0.0);
  EXPECT_NE(error.find("totals.toml:1"), std::string::npos) << error;
  fs::remove_all(dir);
}

TEST(AsAppliedLog, WritesOneLinePerRecordAndRotates) {
  const fs::path dir = temp_dir("as-applied");
  AppliedRecord r;
  r.nozzles = 4;
  r.distance_m = 1.5;
  r.duty_pct = {25, 50, 75, 100};
  r.density = {0.1f, 0.2f, 0.3f, 0.4f};
  r.crop_density = {0.5f, 0.0f, 0.25f, 0.0f};
  {
    AsAppliedLog log(dir, 4096, 3);
    for (int i = 0; i < 400; ++i) {
      r.time = std::chrono::milliseconds(200 * i);
      ASSERT_TRUE(log.write(r));
    }
    log.flush();
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files.size(), 3U) << "older files pruned down to keep_files";
  std::ifstream in(files.back());
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header,
            "time_s,distance_m,speed_m_per_s,pressure_mpa,flow_l_per_min,volume_l,duty_pct_0,"
            "duty_pct_1,"
            "duty_pct_2,duty_pct_3,density_0,density_1,density_2,density_3,crop_density_0,"
            "crop_density_1,crop_density_2,crop_density_3,utc,latitude_deg,longitude_deg,"
            "course_deg,nozzle_width_m,latitude_deg_0,latitude_deg_1,latitude_deg_2,"
            "latitude_deg_3,longitude_deg_0,longitude_deg_1,longitude_deg_2,longitude_deg_3,"
            "rate_l_per_ha_0,rate_l_per_ha_1,rate_l_per_ha_2,rate_l_per_ha_3,speed_m_per_s_0,"
            "speed_m_per_s_1,speed_m_per_s_2,speed_m_per_s_3,seq");
  std::string line;
  std::getline(in, line);
  EXPECT_NE(line.find(",1.5000,"), std::string::npos) << line;
  EXPECT_NE(line.find(",25.0,50.0,75.0,100.0,0.1000,0.2000,0.3000,0.4000,0.5000,0.0000,0.2500,"
                      "0.0000"),
            std::string::npos)
      << line;
  for (const auto& f : files) EXPECT_LE(fs::file_size(f), 4096U + 200U);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace weedspray::daemon
