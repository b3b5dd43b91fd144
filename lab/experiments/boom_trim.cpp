// SPDX-License-Identifier: Apache-2.0
#include "lab/experiments/boom_trim.hpp"
#include "lab/experiments/vocabulary.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace weedspray::lab::experiments {
namespace {

// Relative noise per window assumed until the innovations have taught the filter its own.
constexpr double kInitialNoiseFraction = 0.02;
// An innovation beyond this many sd (a window cut by a duty change, a pressure dip) updates
// the noise estimate but not the parameters.
constexpr double kOutlierSd = 4.0;

bool usable(double x) {
  return std::isfinite(x) && x >= 0.0;
}

}  // namespace

void validate(const BoomTrimConfig& c) {
  auto require = [](bool ok, const char* field) {
    if (!ok) throw std::invalid_argument(std::string("BoomTrimConfig.") + field);
  };
  require(c.prior_gain_sd > 0 && c.prior_gain_sd < 1, "prior_gain_sd must be in (0, 1)");
  require(c.prior_offset_sd > 0 && c.prior_offset_sd <= 50, "prior_offset_sd must be in (0, 50]");
  require(usable(c.gain_drift_per_sqrt_s), "gain_drift_per_sqrt_s must be >= 0");
  require(usable(c.offset_drift_per_sqrt_s), "offset_drift_per_sqrt_s must be >= 0");
  require(c.min_gain > 0 && c.min_gain <= 1, "min_gain must be in (0, 1]");
  require(c.max_gain >= 1 && std::isfinite(c.max_gain), "max_gain must be >= 1");
  require(c.max_offset_pct >= 0 && c.max_offset_pct <= 50, "max_offset_pct must be in [0, 50]");
  require(c.noise_time_constant_s > 0 && std::isfinite(c.noise_time_constant_s),
          "noise_time_constant_s must be > 0");
  require(c.min_noise_fraction > 0 && c.min_noise_fraction < 1,
          "min_noise_fraction must be in (0, 1)");
}

BoomTrim::BoomTrim(const BoomTrimConfig& config) : config_(config) {
  validate(config_);
  reset();
}

void BoomTrim::reset() noexcept {
  theta_ = {1.0, 0.0};
  cov_ = {};
  cov_[0][0] = config_.prior_gain_sd * config_.prior_gain_sd;
  cov_[1][1] = config_.prior_offset_sd * config_.prior_offset_sd;
  noise_var_ = kInitialNoiseFraction * kInitialNoiseFraction;
  windows_ = 0;
}

double BoomTrim::flow_to_ask(double request_l_per_min,
                             double slope_l_per_min_per_pct) const noexcept {
  if (!(request_l_per_min > 0.0) || !std::isfinite(request_l_per_min)) return request_l_per_min;
  const double slope = std::isfinite(slope_l_per_min_per_pct) ? slope_l_per_min_per_pct : 0.0;
  return std::max(0.0, (request_l_per_min - slope * theta_[1]) / theta_[0]);
}

void BoomTrim::add_window(const BoomTrimWindow& w) noexcept {
  if (!usable(w.promised_l) || !usable(w.slope_l_per_pct) || !usable(w.metered_l) ||
      !std::isfinite(w.window_s) || w.window_s <= 0.0)
    return;
  // Random walk: the parameters may have moved since the last window, never beyond their
  // prior's width.
  const auto drift = [&](std::size_t j, double per_sqrt_s, double prior_sd) {
    cov_[j][j] = std::min(cov_[j][j] + per_sqrt_s * per_sqrt_s * w.window_s,
                          std::max(cov_[j][j], prior_sd * prior_sd));
  };
  drift(0, config_.gain_drift_per_sqrt_s, config_.prior_gain_sd);
  drift(1, config_.offset_drift_per_sqrt_s, config_.prior_offset_sd);
  if (w.promised_l <= 0.0) return;

  // Scalar measurement h = (P, S): innovation nu = V - h.theta, its variance S = h C h' + R.
  const std::array<double, 2> h{w.promised_l, w.slope_l_per_pct};
  const std::array<double, 2> ch{cov_[0][0] * h[0] + cov_[0][1] * h[1],
                                 cov_[1][0] * h[0] + cov_[1][1] * h[1]};
  const double hch = h[0] * ch[0] + h[1] * ch[1];
  const double scale2 = w.promised_l * w.promised_l;
  const double floor_var = config_.min_noise_fraction * config_.min_noise_fraction;
  const double s = hch + std::max(noise_var_, floor_var) * scale2;
  const double nu = w.metered_l - (theta_[0] * h[0] + theta_[1] * h[1]);
  ++windows_;

  // Learn the relative noise from what the innovation shows beyond the parameters' own
  // uncertainty (clipped so one outlier cannot blow it up).
  const double alpha = 1.0 - std::exp(-w.window_s / config_.noise_time_constant_s);
  const double limit2 = kOutlierSd * kOutlierSd * s;
  noise_var_ +=
      alpha * (std::max((std::min(nu * nu, limit2) - hch) / scale2, floor_var) - noise_var_);
  if (nu * nu > limit2) return;

  // Kalman gain K = C h / S; theta += K nu; C -= K (C h)'.
  for (std::size_t i = 0; i < 2; ++i) {
    const double k = ch[i] / s;
    theta_[i] += k * nu;
    for (std::size_t j = 0; j < 2; ++j) cov_[i][j] -= k * ch[j];
  }
  theta_[0] = std::clamp(theta_[0], config_.min_gain, config_.max_gain);
  theta_[1] = std::clamp(theta_[1], -config_.max_offset_pct, config_.max_offset_pct);
}

bool BoomTrimWindows::tick(double dt_s, double promised_l_per_min, double slope_l_per_min_per_pct,
                           bool usable, std::uint64_t pulses, double pulses_per_litre,
                           BoomTrimWindow& out) noexcept {
  if (!usable || !std::isfinite(dt_s) || dt_s <= 0.0 || !std::isfinite(promised_l_per_min) ||
      !std::isfinite(slope_l_per_min_per_pct)) {
    started_ = false;  // the window so far is lost; the next usable tick starts one
    return false;
  }
  if (!started_) {
    // The pulses counted up to now belong to ticks before this window.
    started_ = true;
    start_pulses_ = pulses;
    current_ = {};
    min_promise_ = max_promise_ = promised_l_per_min;
    return false;
  }
  current_.promised_l += promised_l_per_min * dt_s / 60.0;
  current_.slope_l_per_pct += slope_l_per_min_per_pct * dt_s / 60.0;
  current_.window_s += dt_s;
  min_promise_ = std::min(min_promise_, promised_l_per_min);
  max_promise_ = std::max(max_promise_, promised_l_per_min);
  if (current_.window_s < window_s_ - 1e-9) return false;
  const bool steady = max_promise_ - min_promise_ <= max_promise_change_ * max_promise_;
  const bool counted = pulses >= start_pulses_ && pulses_per_litre > 0.0;
  current_.metered_l = counted ? static_cast<double>(pulses - start_pulses_) / pulses_per_litre : 0;
  out = current_;
  current_ = {};
  start_pulses_ = pulses;
  min_promise_ = max_promise_ = promised_l_per_min;
  return steady && counted;
}

}  // namespace weedspray::lab::experiments
