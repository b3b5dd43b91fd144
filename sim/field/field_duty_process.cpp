// SPDX-License-Identifier: Apache-2.0
#include "sim/field/field_duty_process.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace weedspray::sim {

FieldDutyProcess::FieldDutyProcess(std::size_t nozzles, std::uint64_t seed,
                                   FieldDutyOptions options)
    : options_(options), rng_(seed), own_(nozzles) {
  if (!(options.correlation_s > 0) || options.common_share < 0 || options.common_share > 1)
    throw std::invalid_argument("field duties: correlation_s > 0 and common_share in 0..1");
  speed_phase_ = std::uniform_real_distribution<double>(0.0, 2.0 * std::numbers::pi)(rng_);
  // Start from the stationary distribution, not from the mean.
  common_ = normal_(rng_);
  for (double& x : own_) x = normal_(rng_);
}

void FieldDutyProcess::advance_to(double t_s) {
  const double dt = t_s - now_s_;
  if (dt <= 0) return;
  now_s_ = t_s;
  // AR(1) sampled exactly over dt: unit variance, autocorrelation exp(-lag / correlation_s).
  const double keep = std::exp(-dt / options_.correlation_s);
  const double fresh = std::sqrt(1.0 - keep * keep);
  common_ = keep * common_ + fresh * normal_(rng_);
  for (double& x : own_) x = keep * x + fresh * normal_(rng_);
}

void FieldDutyProcess::shares_at(double t_s, std::span<double> shares) {
  advance_to(t_s);
  const bool headland = headland_at(t_s);
  const double common_weight = std::sqrt(options_.common_share);
  const double own_weight = std::sqrt(1.0 - options_.common_share);
  const double span = 1.0 - options_.close_below;
  for (std::size_t i = 0; i < shares.size() && i < own_.size(); ++i) {
    const double density =
        std::clamp(options_.mean_density +
                       options_.density_sd * (common_weight * common_ + own_weight * own_[i]),
                   0.0, 1.0);
    if (headland || density < options_.close_below) {
      shares[i] = 0.0;
      continue;
    }
    const double above = span > 0 ? (density - options_.close_below) / span : 1.0;
    shares[i] = std::lerp(options_.min_share, options_.max_share, above);
  }
}

bool FieldDutyProcess::headland_at(double t_s) const {
  if (!(options_.headland_every_s > 0) || !(options_.headland_s > 0)) return false;
  const double into_pass = std::fmod(t_s, options_.headland_every_s);
  return into_pass >= options_.headland_every_s - options_.headland_s;
}

double FieldDutyProcess::speed_factor_at(double t_s) const {
  return 1.0 + options_.speed_swing *
                   std::sin(2.0 * std::numbers::pi * t_s / options_.speed_period_s + speed_phase_);
}

}  // namespace weedspray::sim
