// SPDX-License-Identifier: Apache-2.0
// Camera-to-nozzle scheduling by distance (SPEC §5).
//
// Geometry (pinhole camera, flat ground): the camera is mount_height_m above the ground, its
// optical axis tilted FORWARD by tilt_from_vertical_rad from the vertical (0 = looking straight
// down), vertical field of view vertical_fov_rad. The ray through normalised image row v
// (0 = image top, 1 = bottom) meets the ground at  h * tan(tilt + atan((1 - 2 v) tan(fov/2)))
// ahead of the camera's nadir. The nozzles are camera_to_nozzle_m BEHIND the nadir.
// Zones: the image is split in `rows` equal pixel bands, row 0 = image top (farthest ground),
// and `nozzles` columns. A zone decision of a frame taken at odometer reading d_f covers the
// ground interval [d_f + near, d_f + far) in absolute odometer coordinates.
// Applying: at odometer reading d the ground under the nozzle is x = d - camera_to_nozzle_m.
// A valve takes opening_delay to open and closing_delay to close, so the valve is COMMANDED
// open from d = start + c2n - v * opening_delay to d = end + c2n - v * closing_delay.
// Plan: per nozzle a fixed-capacity ring of intervals (allocated at construction); the newest
// interval wins where they overlap; the oldest is overwritten when full. Gaps (ground no frame
// covered): the valve is closed (GapPolicy::kClose) or keeps the last duty it had
// (GapPolicy::kHoldLast, until a later interval or hold_last_max_m further). Units: m, m/s, s.
#pragma once

#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

namespace weedspray::control {

struct CameraGeometry {
  double mount_height_m = 1.0;
  double tilt_from_vertical_rad = 0.0;  // forward tilt; tilt + fov/2 must be < 90 deg
  double vertical_fov_rad = 0.8;
  double camera_to_nozzle_m = 1.2;  // boom behind the camera's nadir
};

// Ground distances ahead of the camera's nadir (may be negative: behind it).
struct GroundInterval {
  double near_m = 0.0;
  double far_m = 0.0;
};

// Throws std::invalid_argument naming the field (height <= 0, fov outside (0, pi), the top ray
// at or above the horizon, ...).
void validate(const CameraGeometry& geometry);
GroundInterval ground_footprint(const CameraGeometry& geometry) noexcept;
// Ground distance ahead of nadir of normalised image row v (0 top .. 1 bottom).
double ground_distance_of_row(const CameraGeometry& geometry, double v) noexcept;
// Ground interval of zone row `row` of `rows` (row 0 = image top = farthest).
GroundInterval zone_ground_interval(const CameraGeometry& geometry, std::size_t rows,
                                    std::size_t row) noexcept;

enum class GapPolicy { kClose, kHoldLast };

struct NozzleSchedulerConfig {
  CameraGeometry geometry{};
  std::size_t nozzles = 4;
  std::size_t rows = 1;
  double opening_delay_s = 0.03;
  double closing_delay_s = 0.03;
  std::size_t plan_capacity = 64;  // intervals kept per nozzle
  GapPolicy gap_policy = GapPolicy::kClose;
  double hold_last_max_m = 0.5;  // kHoldLast: hold at most this far past an interval's end
};

class NozzleScheduler {
 public:
  // Throws std::invalid_argument naming the field.
  explicit NozzleScheduler(const NozzleSchedulerConfig& config);

  // Pin one frame's decisions: duty_pct is rows x nozzles, row-major (row 0 = image top).
  // frame_odometer_m = Odometry::distance_at(frame timestamp). Size mismatch: ignored, false.
  bool add_frame(double frame_odometer_m, std::span<const double> duty_pct) noexcept;
  // The same on a turn, where each nozzle runs on its own arc: nozzle_odometer_m[n] is the
  // distance nozzle n itself had travelled when the frame was taken (centre line + v_n - v
  // integrated), and duty_at()/value_at() get that nozzle's own odometer and speed. The
  // ground a zone showed near..far ahead of the nadir comes under the nozzle after about
  // near..far + camera_to_nozzle of the NOZZLE's travel (on a 12 m curve, a point 3.2 m ahead
  // of a nozzle 1.5 m off the centre line: within 4 cm; on the centre line's odometer: 40 cm
  // off). Equal odometers are add_frame() above. Size mismatch: false.
  bool add_frame(std::span<const double> nozzle_odometer_m,
                 std::span<const double> duty_pct) noexcept;
  // Pin one interval directly (absolute odometer coordinates of the ground).
  void add_interval(std::size_t nozzle, double ground_start_m, double ground_end_m,
                    double duty_pct) noexcept;

  // Duty to command now for `nozzle`, at odometer reading odometer_m and speed speed_m_per_s.
  double duty_at(std::size_t nozzle, double odometer_m, double speed_m_per_s) const noexcept;
  // The same, for plans that hold a value the caller turns into a command (e.g. weed density
  // -> duty through the rate law): `sprays(value)` says whether that value opens the valve, so
  // a planned value that sprays nothing (below the decision threshold) closes the valve with
  // the closing lead, not the opening one. Returns the planned value to use, 0 for closed.
  template <class Sprays>
  double value_at(std::size_t nozzle, double odometer_m, double speed_m_per_s,
                  Sprays&& sprays) const noexcept;

  // Forget all plans (e.g. vision lost: valves close).
  void clear() noexcept;
  const NozzleSchedulerConfig& config() const noexcept { return config_; }
  // Ground intervals of each zone row, computed once from the geometry.
  const std::vector<GroundInterval>& row_intervals() const noexcept { return row_intervals_; }

 private:
  struct PlannedInterval {
    double start_m = 0.0;
    double end_m = 0.0;
    double duty_pct = 0.0;
  };
  // Duty of the newest interval containing ground point x; false if none.
  bool find(std::size_t nozzle, double x, double& duty) const noexcept;
  // Latest end (and its duty) of intervals ending at or before x, for kHoldLast.
  bool find_last_before(std::size_t nozzle, double x, double& duty) const noexcept;

  // Ground points under the nozzle where an opening and a closing command must look now.
  struct LookAhead {
    double open_m;
    double close_m;
  };
  LookAhead look_ahead(double odometer_m, double speed_m_per_s) const noexcept;

  NozzleSchedulerConfig config_;
  std::vector<GroundInterval> row_intervals_;
  std::vector<PlannedInterval> plans_;  // nozzles x plan_capacity rings
  std::vector<std::size_t> plan_size_;
  std::vector<std::size_t> plan_head_;  // next write slot
};

template <class Sprays>
double NozzleScheduler::value_at(std::size_t nozzle, double odometer_m, double speed_m_per_s,
                                 Sprays&& sprays) const noexcept {
  if (nozzle >= config_.nozzles || !std::isfinite(odometer_m)) return 0.0;
  const LookAhead look = look_ahead(odometer_m, speed_m_per_s);
  // A command takes effect after the opening delay when it opens the valve and after the
  // closing delay when it closes it, so the look-ahead point that reaches a spray patch's edge
  // first must wait for the other one:
  //  - closing slower than opening (the usual case): open while BOTH points need spray — the
  //    nearer opening point starts the spray, the farther closing point ends it in time;
  //  - opening slower: open while EITHER point needs spray.
  // (Patches or gaps shorter than speed x |delay difference| cannot be laid exactly.)
  double value = 0.0;
  double closing = 0.0;
  const bool open_point_sprays = find(nozzle, look.open_m, value) && sprays(value);
  const bool close_point_sprays = find(nozzle, look.close_m, closing) && sprays(closing);
  if (look.close_m > look.open_m) {
    if (open_point_sprays && close_point_sprays) return value;
  } else {
    if (open_point_sprays) return value;
    if (close_point_sprays) return closing;
  }
  if (config_.gap_policy == GapPolicy::kHoldLast) {
    double held = 0.0;
    if (!find(nozzle, look.open_m, value) && find_last_before(nozzle, look.open_m, held) &&
        sprays(held))
      return held;
  }
  return 0.0;
}

}  // namespace weedspray::control
