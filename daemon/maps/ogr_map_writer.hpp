// SPDX-License-Identifier: Apache-2.0
// Writes the map layers with GDAL/OGR, in WGS84 (EPSG:4326, longitude/latitude order):
//   sprayed       one polygon per nozzle stretch (stretches.hpp)
//   weed_density  one square per grid cell (density_grid.hpp)
// GeoPackage: OUT is one file holding both layers, written in one transaction. GeoJSON and
// Shapefile hold one layer per file: OUT is a folder with sprayed.geojson and
// weed_density.geojson, or sprayed.shp and weed_density.shp (+ .shx .dbf .prj).
// Field names fit the Shapefile's 10 characters, so every format has the same fields. A map of
// several boards' logs has one more field on `sprayed`, last: `board`.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "daemon/maps/density_grid.hpp"
#include "daemon/maps/stretches.hpp"

namespace weedspray::daemon::maps {

enum class MapFormat { kGeoJson, kGpkg, kShapefile };

// "geojson" | "gpkg" | "shp"; throws std::invalid_argument naming the accepted values.
MapFormat parse_map_format(const std::string& name);

class OgrMapWriter {
 public:
  // Throws std::runtime_error naming OUT when it exists (and !overwrite) or cannot be created.
  // `board_field`: the sprayed layer has the field `board`.
  OgrMapWriter(MapFormat format, const std::filesystem::path& out, bool overwrite,
               bool board_field = false);
  ~OgrMapWriter();
  OgrMapWriter(const OgrMapWriter&) = delete;
  OgrMapWriter& operator=(const OgrMapWriter&) = delete;

  // `board` goes into the field `board` where the layer has it.
  void add(const Stretch& stretch, const std::string& board = {});
  void add(const DensityCell& cell);
  // Commits and closes every file; throws std::runtime_error naming the file on failure.
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace weedspray::daemon::maps
