// A field for the savings experiment: the bundled images' zone densities, computed with
// weedspray_vision's pipeline (2 rows along travel x 4 nozzle columns per image, wheat paper
// layout), laid one after another along a track.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace weedspray::lab {

// Zones in track order: image i contributes its near (bottom) row, then its far row. Images sorted
// by file name. Throws std::runtime_error naming the directory/file on failure.
std::vector<std::array<double, 4>> field_zone_densities(const std::string& images_dir);

}  // namespace weedspray::lab
