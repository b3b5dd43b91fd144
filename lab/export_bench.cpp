// SPDX-License-Identifier: Apache-2.0
// weedspray-export-bench: times `weedspray-export-map` on a synthetic day's log. Writes an
// as-applied log with the daemon's own writer (AsAppliedLog): N hours, the daemon's record rate
// (pwm.frequency_hz records a second), a boustrophedon field track with semicircular headland
// turns, patchy weeds so only part of the nozzles spray; then exports it in each format
// --repeat times and prints mean / sd / worst seconds, polygons, cells and file sizes.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/maps/map_export.hpp"
#include "daemon/records/as_applied_log.hpp"
#include "daemon/sprayer/geometry.hpp"

namespace {

using namespace weedspray::daemon;
namespace fs = std::filesystem;

// Weed patches: 8 m cells, ~30 % of them hold a patch of some density fading from its centre.
double weed_density_at(double north_m, double east_m) {
  const auto cell_n = static_cast<std::int64_t>(std::floor(north_m / 8.0));
  const auto cell_e = static_cast<std::int64_t>(std::floor(east_m / 8.0));
  std::uint64_t h = static_cast<std::uint64_t>(cell_n) * 0x9E3779B97F4A7C15ULL ^
                    static_cast<std::uint64_t>(cell_e) * 0xC2B2AE3D27D4EB4FULL;
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 32;
  if ((h & 0xff) > 77) return 0.002;  // ~70 % clean ground
  const double peak = 0.05 + 0.3 * static_cast<double>((h >> 8) & 0xff) / 255.0;
  const double dn = north_m - (static_cast<double>(cell_n) + 0.5) * 8.0;
  const double de = east_m - (static_cast<double>(cell_e) + 0.5) * 8.0;
  return peak * std::max(0.0, 1.0 - std::hypot(dn, de) / 4.0);
}

struct Pose {
  double north = 0, east = 0, course_deg = 0, yaw_deg_per_s = 0;
};

// Rows `row_m` long heading north then south, `spacing_m` apart, joined by semicircles.
Pose track_at(double s, double row_m, double spacing_m, double speed) {
  const double turn_m = std::numbers::pi * spacing_m / 2;
  const double lap = row_m + turn_m;
  const auto k = static_cast<std::int64_t>(std::floor(s / lap));
  const double u = s - static_cast<double>(k) * lap;
  const bool north_bound = k % 2 == 0;
  const double east0 = static_cast<double>(k) * spacing_m;
  Pose p;
  if (u < row_m) {
    p.north = north_bound ? u : row_m - u;
    p.east = east0;
    p.course_deg = north_bound ? 0 : 180;
    return p;
  }
  const double a = (u - row_m) / (spacing_m / 2);  // radians turned
  const double r = spacing_m / 2;
  p.east = east0 + r - r * std::cos(a);
  p.north = north_bound ? row_m + r * std::sin(a) : -r * std::sin(a);
  p.course_deg = north_bound ? a * 180 / std::numbers::pi : 180 + a * 180 / std::numbers::pi;
  // North-bound turns to the east are clockwise; south-bound turns to the east counter-clockwise.
  p.yaw_deg_per_s = (north_bound ? 1 : -1) * speed / r * 180 / std::numbers::pi;
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"weedspray-export-bench: export time of a synthetic day's as-applied log"};
  double hours = 8;
  int nozzles = 24;
  double record_hz = default_config().pwm.frequency_hz;
  double speed = 2.0;
  int repeat = 3;
  std::string work = (fs::temp_directory_path() / "weedspray-export-bench").string();
  app.add_option("--hours", hours, "hours of spraying")->capture_default_str();
  app.add_option("--nozzles", nozzles, "nozzles on the boom")
      ->capture_default_str()
      ->check(CLI::Range(1, static_cast<int>(weedspray::io::kMaxValves)));
  app.add_option("--record-hz", record_hz, "records a second (the daemon: pwm.frequency_hz)")
      ->capture_default_str();
  app.add_option("--speed", speed, "ground speed, m/s")->capture_default_str();
  app.add_option("--repeat", repeat, "exports per format")->capture_default_str();
  app.add_option("--work", work, "scratch folder (replaced)")->capture_default_str();
  bool keep = false;
  app.add_flag("--keep", keep, "leave the log and the maps in --work (to look at them)");
  bool json = false;
  app.add_flag("--json", json, "print one JSON object instead of text");
  CLI11_PARSE(app, argc, argv);

  const fs::path dir = fs::path(work) / "log";
  fs::remove_all(work);
  Config config = default_config();
  config.boom.nozzles = nozzles;
  const double width = config.boom.nozzle_width_m;
  const LatLon origin{52.0, 5.0};
  const auto records = static_cast<std::int64_t>(hours * 3600 * record_hz);
  const auto t0 = std::chrono::steady_clock::now();
  std::uint64_t open_nozzle_records = 0;
  {
    AsAppliedLog log(dir, static_cast<std::uintmax_t>(config.log.rotate_bytes), 100000,
                     NozzlePlacement{width, {1.5, 0.0}});
    AppliedRecord r;
    r.nozzles = static_cast<std::uint32_t>(nozzles);
    const std::int64_t utc0 = *parse_utc("2026-06-24T06:00:00Z");
    const double spacing = width * nozzles;
    for (std::int64_t i = 0; i < records; ++i) {
      const double t = static_cast<double>(i) / record_hz;
      const double s = speed * t;
      const Pose pose = track_at(s, 400.0, spacing, speed);
      r.time = std::chrono::nanoseconds(static_cast<std::int64_t>(t * 1e9));
      r.speed_m_per_s = speed;
      r.distance_m = s;
      // The antenna's fix arrived 50 ms before the record (a 10 Hz receiver, mid-period).
      const LatLon antenna = step(origin, pose.north, pose.east);
      const double back = speed * 0.05;
      const double c = pose.course_deg * std::numbers::pi / 180;
      const LatLon fix_at = step(antenna, -back * std::cos(c), -back * std::sin(c));
      r.fix.latitude_deg = fix_at.latitude_deg;
      r.fix.longitude_deg = fix_at.longitude_deg;
      r.fix.speed_m_per_s = speed;
      r.fix.course_deg = pose.course_deg;
      r.fix.mode = weedspray::io::GnssFixMode::k3D;
      r.fix.utc_ns = utc0 + static_cast<std::int64_t>((t - 0.05) * 1e9);
      r.fix_time = r.time - std::chrono::milliseconds(50);
      r.fix_usable = true;
      r.yaw_rate_deg_per_s = pose.yaw_deg_per_s;
      double flow = 0;
      for (int n = 0; n < nozzles; ++n) {
        const double offset = nozzle_right_offset_m(config.boom, static_cast<std::size_t>(n));
        const double right = c + std::numbers::pi / 2;
        const double density = weed_density_at(pose.north + offset * std::cos(right),
                                               pose.east + offset * std::sin(right));
        const double duty = density > 0.02 ? std::min(100.0, 40 + 200 * density) : 0;
        r.duty_pct[n] = static_cast<float>(duty);
        r.density[n] = static_cast<float>(density);
        r.crop_density[n] = static_cast<float>(0.2 + 0.1 * std::sin(pose.north / 3));
        r.nozzle_speed_m_per_s[n] =
            static_cast<float>(speed + pose.yaw_deg_per_s * std::numbers::pi / 180 * offset);
        r.nozzle_flow_l_per_min[n] = static_cast<float>(duty / 100 * 1.2);
        flow += r.nozzle_flow_l_per_min[n];
        open_nozzle_records += duty > 0 ? 1 : 0;
      }
      r.flow_l_per_min = flow;
      r.volume_l = flow / 60 / record_hz;
      if (!log.write(r)) {
        std::fprintf(stderr, "cannot write %s\n", log.current_file().c_str());
        return 1;
      }
    }
    log.flush();
  }
  std::uintmax_t log_bytes = 0;
  std::size_t log_files = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    log_bytes += e.file_size();
    ++log_files;
  }
  const double spraying_pct =
      100.0 * static_cast<double>(open_nozzle_records) / static_cast<double>(records * nozzles);
  const double write_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (json) {
    std::printf(
        "{\"hours\": %.2f, \"nozzles\": %d, \"record_hz\": %.2f, \"records\": %lld, "
        "\"spraying_pct\": %.1f, \"log_files\": %zu, \"log_mb\": %.1f, \"write_s\": %.2f, "
        "\"exports\": [",
        hours, nozzles, record_hz, static_cast<long long>(records), spraying_pct, log_files,
        static_cast<double>(log_bytes) / 1e6, write_s);
  } else {
    std::printf(
        "synthetic log: %.1f h x %d nozzles at %.0f records/s = %lld records, %.0f%% of nozzle "
        "records spraying, %zu files, %.0f MB, written in %.1f s\n",
        hours, nozzles, record_hz, static_cast<long long>(records), spraying_pct, log_files,
        static_cast<double>(log_bytes) / 1e6, write_s);
  }

  const char* separator = "";
  for (const char* format : {"gpkg", "shp", "geojson"}) {
    std::vector<double> seconds;
    maps::ExportSummary summary;
    const fs::path out = fs::path(work) / (std::string("map.") + format);
    for (int k = 0; k < repeat; ++k) {
      maps::ExportOptions o;
      o.log_dirs = {dir};
      o.out = out;
      o.format = maps::parse_map_format(format);
      o.overwrite = true;
      const auto start = std::chrono::steady_clock::now();
      summary = maps::export_map(o);
      seconds.push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    double mean = 0, worst = 0;
    for (double s : seconds) {
      mean += s / static_cast<double>(seconds.size());
      worst = std::max(worst, s);
    }
    double var = 0;
    for (double s : seconds) var += (s - mean) * (s - mean);
    const double sd =
        seconds.size() > 1 ? std::sqrt(var / static_cast<double>(seconds.size() - 1)) : 0;
    std::uintmax_t bytes = 0;
    if (fs::is_directory(out)) {
      for (const auto& e : fs::directory_iterator(out)) bytes += e.file_size();
    } else {
      bytes = fs::file_size(out);
    }
    if (json) {
      std::printf(
          "%s{\"format\": \"%s\", \"runs\": %d, \"mean_s\": %.3f, \"sd_s\": %.3f, "
          "\"worst_s\": %.3f, \"polygons\": %llu, \"cells\": %llu, \"volume_l\": %.1f, "
          "\"area_ha\": %.3f, \"output_mb\": %.1f}",
          separator, format, repeat, mean, sd, worst,
          static_cast<unsigned long long>(summary.stretches),
          static_cast<unsigned long long>(summary.cells), summary.volume_l, summary.area_m2 / 10000,
          static_cast<double>(bytes) / 1e6);
      separator = ", ";
      continue;
    }
    std::printf(
        "%-7s export: mean %.2f s, sd %.2f s, worst %.2f s over %d runs; %llu polygons, %llu "
        "cells, %.0f L on %.2f ha; %.0f MB\n",
        format, mean, sd, worst, repeat, static_cast<unsigned long long>(summary.stretches),
        static_cast<unsigned long long>(summary.cells), summary.volume_l, summary.area_m2 / 10000,
        static_cast<double>(bytes) / 1e6);
  }
  if (json) std::printf("]}\n");
  if (!keep) fs::remove_all(work);
  return 0;
}
