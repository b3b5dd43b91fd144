// SPDX-License-Identifier: Apache-2.0
// Configuration -> the control library's camera geometry.
#pragma once

#include <cstddef>
#include <numbers>

#include "control/nozzle_scheduler.hpp"
#include "daemon/config/config.hpp"

namespace weedspray::daemon {

inline control::CameraGeometry camera_geometry(const CameraSection& camera) {
  control::CameraGeometry g;
  g.mount_height_m = camera.mount_height_m;
  g.tilt_from_vertical_rad = camera.tilt_deg * std::numbers::pi / 180.0;
  g.vertical_fov_rad = camera.vfov_deg * std::numbers::pi / 180.0;
  g.camera_to_nozzle_m = camera.distance_to_nozzles_m;
  return g;
}

// Lateral offset of nozzle n from the boom's centre, metres, positive to the RIGHT looking
// forward. Nozzle 0 is the leftmost; the nozzles sit side by side, nozzle_width_m apart.
inline double nozzle_right_offset_m(const BoomSection& boom, std::size_t n) {
  return (static_cast<double>(n) - 0.5 * static_cast<double>(boom.nozzles - 1)) *
         boom.nozzle_width_m;
}

// Sim speed profile (speed at simulated time t_s).
double sim_speed_m_per_s(const SimSection& sim, double t_s);

}  // namespace weedspray::daemon
