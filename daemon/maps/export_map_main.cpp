// SPDX-License-Identifier: Apache-2.0
// weedspray-export-map: the as-applied log -> a map a farm's GIS opens (QGIS: drag the file in);
// several boards' logs (one --dir each) -> one map of the whole machine.
// Its own program, not part of sprayctl, because GDAL loads ~200 shared libraries: `sprayctl
// status` stays quick, and `sprayctl export-map` runs this one.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/maps/map_export.hpp"

namespace {

using namespace weedspray::daemon;

std::int64_t utc_argument(const std::string& option, const std::string& text) {
  const std::optional<std::int64_t> utc = parse_utc(text);
  if (!utc)
    throw std::runtime_error(option + " " + text +
                             ": not a UTC time (2026-06-24, 2026-06-24T14:30 or "
                             "2026-06-24T14:30:00.000Z)");
  return *utc;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "weedspray-export-map: the as-applied log as a map in WGS84 (EPSG:4326), two layers:\n"
      "  sprayed       per-nozzle sprayed polygons, one per stretch (ends when the nozzle\n"
      "                closes, the fix is lost, or at --max-stretch-m): nozzle, utc_start,\n"
      "                utc_end, rate_l_ha, volume_l, area_m2, duty_pct, weed_dens, crop_dens,\n"
      "                speed_m_s; with several --dir also board (the folder's name)\n"
      "  weed_density  a grid of --cell-m squares: mean weed_dens and crop_dens of every\n"
      "                nozzle patch in the cell (sprayed or not), samples\n"
      "OUT: gpkg: one GeoPackage file with both layers; geojson: a folder holding\n"
      "sprayed.geojson and weed_density.geojson; shp: a folder holding sprayed.shp and\n"
      "weed_density.shp (with .shx .dbf .prj).",
      "weedspray-export-map"};
  maps::ExportOptions options;
  std::string format, from, to;
  std::vector<std::string> dirs;
  std::string config_path = kDefaultConfigPath;
  std::string out;
  app.add_option("--format", format, "geojson, gpkg or shp")->required();
  app.add_option("--from", from, "first record's UTC time (ISO 8601, e.g. 2026-06-24T14:30Z)");
  app.add_option("--to", to, "last record's UTC time (ISO 8601)");
  app.add_option("--dir", dirs,
                 "as-applied log folder (default: the configuration's); once per board of the "
                 "machine (copies of each board's log folder) for one map of them all")
      ->allow_extra_args(false);
  app.add_option("--config", config_path, "configuration whose log folder is read")
      ->capture_default_str();
  app.add_option("--cell-m", options.cell_m, "weed_density grid cell size, metres")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1000.0));
  app.add_option("--max-stretch-m", options.stretch.max_length_m,
                 "longest sprayed polygon along travel, metres")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 10000.0));
  app.add_flag("--overwrite", options.overwrite, "replace OUT's map files if they exist");
  app.add_option("OUT", out, "output file (gpkg) or folder (geojson, shp)")->required();
  CLI11_PARSE(app, argc, argv);

  try {
    options.format = maps::parse_map_format(format);
    if (!from.empty()) options.from_utc_ns = utc_argument("--from", from);
    if (!to.empty()) options.to_utc_ns = utc_argument("--to", to);
    options.out = out;
    if (dirs.empty()) {
      options.log_dirs = {load_config_without_vision(config_path).as_applied_dir()};
    } else {
      options.log_dirs.assign(dirs.begin(), dirs.end());
    }
    const auto start = std::chrono::steady_clock::now();
    const maps::ExportSummary s = maps::export_map(options);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf(
        "%s: %llu sprayed polygons (%.1f L on %.1f m2), %llu weed_density cells; %llu "
        "records (%llu with a position) from %zu files%s in %.2f s\n",
        out.c_str(), static_cast<unsigned long long>(s.stretches), s.volume_l, s.area_m2,
        static_cast<unsigned long long>(s.cells), static_cast<unsigned long long>(s.records),
        static_cast<unsigned long long>(s.records_with_position), s.files,
        dirs.size() > 1 ? (" of " + std::to_string(dirs.size()) + " boards").c_str() : "", seconds);
    for (const std::filesystem::path& dir : s.dirs_without_position)
      std::fprintf(stderr,
                   "weedspray-export-map: no record with a position in %s%s (no GNSS fix?)\n",
                   dir.c_str(), from.empty() && to.empty() ? "" : " in the window");
  } catch (const std::exception& error) {
    std::cerr << "weedspray-export-map: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
