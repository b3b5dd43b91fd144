// SPDX-License-Identifier: Apache-2.0
#include "control/nozzle_scheduler.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace weedspray::control {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

}  // namespace

void validate(const CameraGeometry& g) {
  require(std::isfinite(g.mount_height_m) && g.mount_height_m > 0.0,
          "camera geometry: mount_height_m must be > 0");
  require(std::isfinite(g.vertical_fov_rad) && g.vertical_fov_rad > 0.0 &&
              g.vertical_fov_rad < std::numbers::pi,
          "camera geometry: vertical_fov_rad must be in (0, pi)");
  require(std::isfinite(g.tilt_from_vertical_rad), "camera geometry: tilt must be finite");
  // The top ray must hit the ground well ahead (about 84 deg from vertical at most), and the
  // bottom ray must not point backwards above the horizon.
  const double top = g.tilt_from_vertical_rad + g.vertical_fov_rad / 2.0;
  const double bottom = g.tilt_from_vertical_rad - g.vertical_fov_rad / 2.0;
  require(
      top < std::numbers::pi / 2.0 * 0.94,
      "camera geometry: tilt + fov/2 reaches the horizon (the top of the image sees no ground)");
  require(bottom > -std::numbers::pi / 2.0 * 0.94,
          "camera geometry: tilt - fov/2 reaches the horizon behind the camera");
  require(std::isfinite(g.camera_to_nozzle_m),
          "camera geometry: camera_to_nozzle_m must be finite");
}

double ground_distance_of_row(const CameraGeometry& g, double v) noexcept {
  const double angle =
      g.tilt_from_vertical_rad + std::atan((1.0 - 2.0 * v) * std::tan(g.vertical_fov_rad / 2.0));
  return g.mount_height_m * std::tan(angle);
}

GroundInterval ground_footprint(const CameraGeometry& g) noexcept {
  return GroundInterval{ground_distance_of_row(g, 1.0), ground_distance_of_row(g, 0.0)};
}

GroundInterval zone_ground_interval(const CameraGeometry& g, std::size_t rows,
                                    std::size_t row) noexcept {
  if (rows == 0 || row >= rows) return GroundInterval{};
  const double v_top = static_cast<double>(row) / static_cast<double>(rows);
  const double v_bottom = static_cast<double>(row + 1) / static_cast<double>(rows);
  return GroundInterval{ground_distance_of_row(g, v_bottom), ground_distance_of_row(g, v_top)};
}

NozzleScheduler::NozzleScheduler(const NozzleSchedulerConfig& config) : config_(config) {
  validate(config.geometry);
  require(config.nozzles >= 1 && config.nozzles <= 32,
          "nozzle scheduler: nozzles must be 1..32, got " + std::to_string(config.nozzles));
  require(config.rows >= 1 && config.rows <= 16,
          "nozzle scheduler: rows must be 1..16, got " + std::to_string(config.rows));
  require(std::isfinite(config.opening_delay_s) && config.opening_delay_s >= 0.0 &&
              config.opening_delay_s < 1.0,
          "nozzle scheduler: opening_delay_s must be in [0, 1) s");
  require(std::isfinite(config.closing_delay_s) && config.closing_delay_s >= 0.0 &&
              config.closing_delay_s < 1.0,
          "nozzle scheduler: closing_delay_s must be in [0, 1) s");
  require(config.plan_capacity >= 1 && config.plan_capacity <= 4096,
          "nozzle scheduler: plan_capacity must be 1..4096");
  require(std::isfinite(config.hold_last_max_m) && config.hold_last_max_m >= 0.0,
          "nozzle scheduler: hold_last_max_m must be >= 0");
  for (std::size_t r = 0; r < config.rows; ++r) {
    row_intervals_.push_back(zone_ground_interval(config.geometry, config.rows, r));
  }
  plans_.resize(config.nozzles * config.plan_capacity);
  plan_size_.assign(config.nozzles, 0);
  plan_head_.assign(config.nozzles, 0);
}

void NozzleScheduler::clear() noexcept {
  std::fill(plan_size_.begin(), plan_size_.end(), 0);
  std::fill(plan_head_.begin(), plan_head_.end(), 0);
}

bool NozzleScheduler::add_frame(double frame_odometer_m,
                                std::span<const double> duty_pct) noexcept {
  if (duty_pct.size() != config_.rows * config_.nozzles || !std::isfinite(frame_odometer_m)) {
    return false;
  }
  // Far rows first, so the near row — imaged at a steeper angle — is the newest on overlap.
  for (std::size_t r = 0; r < config_.rows; ++r) {
    const GroundInterval& zone = row_intervals_[r];
    for (std::size_t n = 0; n < config_.nozzles; ++n) {
      add_interval(n, frame_odometer_m + zone.near_m, frame_odometer_m + zone.far_m,
                   duty_pct[r * config_.nozzles + n]);
    }
  }
  return true;
}

bool NozzleScheduler::add_frame(std::span<const double> nozzle_odometer_m,
                                std::span<const double> duty_pct) noexcept {
  if (duty_pct.size() != config_.rows * config_.nozzles ||
      nozzle_odometer_m.size() != config_.nozzles) {
    return false;
  }
  for (std::size_t r = 0; r < config_.rows; ++r) {
    const GroundInterval& zone = row_intervals_[r];
    for (std::size_t n = 0; n < config_.nozzles; ++n) {
      add_interval(n, nozzle_odometer_m[n] + zone.near_m, nozzle_odometer_m[n] + zone.far_m,
                   duty_pct[r * config_.nozzles + n]);
    }
  }
  return true;
}

void NozzleScheduler::add_interval(std::size_t nozzle, double ground_start_m, double ground_end_m,
                                   double duty_pct) noexcept {
  if (nozzle >= config_.nozzles || !std::isfinite(ground_start_m) || !std::isfinite(ground_end_m) ||
      !(ground_end_m > ground_start_m)) {
    return;
  }
  const double duty = std::isfinite(duty_pct) ? std::clamp(duty_pct, 0.0, 100.0) : 0.0;
  const std::size_t capacity = config_.plan_capacity;
  plans_[nozzle * capacity + plan_head_[nozzle]] =
      PlannedInterval{ground_start_m, ground_end_m, duty};
  plan_head_[nozzle] = (plan_head_[nozzle] + 1) % capacity;
  plan_size_[nozzle] = std::min(plan_size_[nozzle] + 1, capacity);
}

bool NozzleScheduler::find(std::size_t nozzle, double x, double& duty) const noexcept {
  const std::size_t capacity = config_.plan_capacity;
  for (std::size_t age = 0; age < plan_size_[nozzle]; ++age) {
    const PlannedInterval& p =
        plans_[nozzle * capacity + (plan_head_[nozzle] + capacity - 1 - age) % capacity];
    if (x >= p.start_m && x < p.end_m) {
      duty = p.duty_pct;
      return true;
    }
  }
  return false;
}

bool NozzleScheduler::find_last_before(std::size_t nozzle, double x, double& duty) const noexcept {
  const std::size_t capacity = config_.plan_capacity;
  double latest_end = -1e300;
  bool found = false;
  for (std::size_t age = 0; age < plan_size_[nozzle]; ++age) {
    const PlannedInterval& p =
        plans_[nozzle * capacity + (plan_head_[nozzle] + capacity - 1 - age) % capacity];
    if (p.end_m <= x && p.end_m > latest_end) {
      latest_end = p.end_m;
      duty = p.duty_pct;
      found = true;
    }
  }
  return found && x - latest_end <= config_.hold_last_max_m;
}

NozzleScheduler::LookAhead NozzleScheduler::look_ahead(double odometer_m,
                                                       double speed_m_per_s) const noexcept {
  const double speed = std::isfinite(speed_m_per_s) ? std::max(0.0, speed_m_per_s) : 0.0;
  const double under_nozzle = odometer_m - config_.geometry.camera_to_nozzle_m;
  // Command early by the distance travelled while the valve moves.
  return {under_nozzle + speed * config_.opening_delay_s,
          under_nozzle + speed * config_.closing_delay_s};
}

double NozzleScheduler::duty_at(std::size_t nozzle, double odometer_m,
                                double speed_m_per_s) const noexcept {
  return value_at(nozzle, odometer_m, speed_m_per_s, [](double duty) { return duty > 0.0; });
}

}  // namespace weedspray::control
