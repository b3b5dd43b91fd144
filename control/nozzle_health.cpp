#include "control/nozzle_health.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace weedspray::control {

void validate(const NozzleHealthConfig& c) {
  auto require = [](bool ok, const char* field) {
    if (!ok) throw std::invalid_argument(std::string("NozzleHealthConfig.") + field);
  };
  require(c.nozzles >= 1 && c.nozzles <= kMaxHealthNozzles, "nozzles must be in [1, 8]");
  require(c.baseline_s > 0, "baseline_s must be > 0");
  require(c.time_constant_s > 0, "time_constant_s must be > 0");
  require(c.alarm_fraction > 0 && c.alarm_fraction < 1, "alarm_fraction must be in (0, 1)");
  require(c.alarm_hold_s >= 0, "alarm_hold_s must be >= 0");
  require(c.min_open_s >= 0, "min_open_s must be >= 0");
}

NozzleHealth::NozzleHealth(const NozzleHealthConfig& config) : config_(config) {
  validate(config_);
  reset();
}

void NozzleHealth::reset() noexcept {
  base_s_ = {};
  base_b_ = {};
  run_s_ = {};
  run_b_ = {};
  open_weight_ = {};
  baseline_.fill(0.0);
  current_.fill(0.0);
  sprayed_s_ = 0.0;
  baseline_ready_ = false;
  outside_s_ = 0.0;
  candidate_ = -1;
  alarmed_ = -1;
}

bool NozzleHealth::solve(const Matrix& s, const Vector& b, Vector& x) const noexcept {
  const std::size_t n = config_.nozzles;
  Matrix a = s;
  Vector y = b;
  for (std::size_t col = 0; col < n; ++col) {
    std::size_t pivot = col;
    for (std::size_t r = col + 1; r < n; ++r)
      if (std::abs(a[r][col]) > std::abs(a[pivot][col])) pivot = r;
    if (!(std::abs(a[pivot][col]) > 1e-12)) return false;
    std::swap(a[col], a[pivot]);
    std::swap(y[col], y[pivot]);
    for (std::size_t r = col + 1; r < n; ++r) {
      const double f = a[r][col] / a[col][col];
      for (std::size_t k = col; k < n; ++k) a[r][k] -= f * a[col][k];
      y[r] -= f * y[col];
    }
  }
  for (std::size_t i = n; i-- > 0;) {
    double v = y[i];
    for (std::size_t k = i + 1; k < n; ++k) v -= a[i][k] * x[k];
    x[i] = v / a[i][i];
  }
  return true;
}

void NozzleHealth::add_window(std::span<const double> open_s, double metered_l,
                              double window_s) noexcept {
  if (!(window_s > 0.0) || !std::isfinite(metered_l)) return;
  const std::size_t n = std::min(config_.nozzles, open_s.size());
  bool any_open = false;
  for (std::size_t i = 0; i < n; ++i) any_open |= open_s[i] > 0.0;
  if (!any_open) return;  // nothing sprays: nothing to learn (and the meter coasts)
  const double keep = std::exp(-window_s / config_.time_constant_s);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < n; ++k) {
      const double aa = open_s[i] * open_s[k];
      if (!baseline_ready_) base_s_[i][k] += aa;
      run_s_[i][k] = keep * run_s_[i][k] + aa;
    }
    if (!baseline_ready_) base_b_[i] += open_s[i] * metered_l;
    run_b_[i] = keep * run_b_[i] + open_s[i] * metered_l;
    open_weight_[i] = keep * open_weight_[i] + open_s[i];
  }
  sprayed_s_ += window_s;
  if (!baseline_ready_) {
    if (sprayed_s_ < config_.baseline_s) return;
    baseline_ready_ = solve(base_s_, base_b_, baseline_);
    if (!baseline_ready_) return;
  }
  if (!solve(run_s_, run_b_, current_)) return;
  // The nozzle furthest from its baseline among those open enough to be judged.
  int worst = -1;
  double worst_dev = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (open_weight_[i] < config_.min_open_s || !(baseline_[i] > 0.0)) continue;
    const double dev = std::abs(current_[i] / baseline_[i] - 1.0);
    if (dev > worst_dev) {
      worst_dev = dev;
      worst = static_cast<int>(i);
    }
  }
  if (worst >= 0 && worst_dev > config_.alarm_fraction) {
    outside_s_ = worst == candidate_ ? outside_s_ + window_s : window_s;
    candidate_ = worst;
    if (outside_s_ >= config_.alarm_hold_s) alarmed_ = worst;
  } else {
    outside_s_ = 0.0;
    candidate_ = -1;
  }
}

double NozzleHealth::ratio(std::size_t nozzle) const noexcept {
  if (!baseline_ready_ || nozzle >= config_.nozzles || !(baseline_[nozzle] > 0.0)) return 1.0;
  return current_[nozzle] / baseline_[nozzle];
}

}  // namespace weedspray::control
