// SPDX-License-Identifier: Apache-2.0
#include "control/nozzle_health.hpp"

#include "control/small_linear_system.hpp"

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
  require(c.judge == NozzleJudge::kBand || c.judge == NozzleJudge::kCusum,
          "judge must be kBand or kCusum");
  require(c.alarm_hold_s >= 0, "alarm_hold_s must be >= 0");
  require(c.min_open_s >= 0, "min_open_s must be >= 0");
  require(c.alarm_threshold > 0 && std::isfinite(c.alarm_threshold),
          "alarm_threshold must be > 0 and finite");
  require(c.common_time_constant_s > 0, "common_time_constant_s must be > 0");
  require(c.isolation_margin >= 0 && std::isfinite(c.isolation_margin),
          "isolation_margin must be >= 0 and finite");
  require(c.duty_mask >= 0 && c.duty_mask <= 1, "duty_mask must be in [0, 1]");
  require(c.min_pulse_s >= 0 && std::isfinite(c.min_pulse_s), "min_pulse_s must be >= 0");
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
  base_vv_ = 0.0;
  base_windows_ = 0.0;
  base_v_ = 0.0;
  baseline_.fill(0.0);
  current_.fill(0.0);
  noise_var_ = 0.0;
  common_num_ = 0.0;
  common_den_ = 0.0;
  base_open_s_ = 0.0;
  recent_open_ = {};
  recent_slot_ = 0;
  recent_windows_ = 0;
  masked_windows_left_ = 0;
  cusum_down_.fill(0.0);
  cusum_up_.fill(0.0);
  open_weight_ = {};
  outside_s_ = 0.0;
  candidate_ = -1;
  sprayed_s_ = 0.0;
  baseline_ready_ = false;
  alarmed_ = -1;
  alarmed_low_ = false;
}

bool NozzleHealth::solve(const Matrix& s, const Vector& b, Vector& x) const noexcept {
  return solve_small_system(s, b, config_.nozzles, x);
}

void NozzleHealth::add_window(std::span<const double> open_s, double metered_l,
                              double window_s) noexcept {
  if (!(window_s > 0.0) || !std::isfinite(metered_l)) return;
  const std::size_t n = std::min(config_.nozzles, open_s.size());
  bool any_open = false;
  for (std::size_t i = 0; i < n; ++i) any_open |= open_s[i] > 0.0;
  if (!any_open) return;  // nothing sprays: nothing to learn (and the meter coasts)
  const double keep = std::exp(-window_s / config_.time_constant_s);
  double open_sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) open_sum += open_s[i];
  // The last PWM period's windows (nozzles x window; exact sums: a forgotten average of one
  // staggered nozzle's windows would swing with its phase): each nozzle's open time in it, the
  // length of its pulse.
  recent_open_[recent_slot_] = {};
  for (std::size_t i = 0; i < n; ++i) recent_open_[recent_slot_][i] = open_s[i];
  recent_slot_ = (recent_slot_ + 1) % config_.nozzles;
  if (recent_windows_ < config_.nozzles) ++recent_windows_;
  double period_open_s = 0.0;
  bool short_pulse = false;
  for (std::size_t i = 0; i < n; ++i) {
    double pulse_s = 0.0;
    for (std::size_t w = 0; w < config_.nozzles; ++w) pulse_s += recent_open_[w][i];
    period_open_s += pulse_s;
    short_pulse |= pulse_s > 0.0 && pulse_s < config_.min_pulse_s;
  }
  const double recent_duty =
      period_open_s / (static_cast<double>(config_.nozzles * recent_windows_) * window_s);
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
    base_vv_ += metered_l * metered_l;
    base_v_ += metered_l;
    base_windows_ += 1.0;
    base_open_s_ += open_sum;
    if (sprayed_s_ < config_.baseline_s || base_windows_ <= static_cast<double>(n)) return;
    baseline_ready_ = solve(base_s_, base_b_, baseline_);
    if (!baseline_ready_) return;
    // Residual sum of squares of the fit: sum V^2 - b . c0 (normal equations).
    double rss = base_vv_;
    for (std::size_t i = 0; i < n; ++i) rss -= base_b_[i] * baseline_[i];
    // Floor: 1 % of the mean window volume, so an exact meter cannot make every window
    // decisive (and s2 never 0).
    const double mean_v = base_v_ / base_windows_;
    noise_var_ = std::max(rss / (base_windows_ - static_cast<double>(n)), 1e-4 * mean_v * mean_v);
    solve(run_s_, run_b_, current_);
    return;  // judged from the next window on
  }
  solve(run_s_, run_b_, current_);  // singular (all at 50 %): the last estimate stays
  if (config_.judge == NozzleJudge::kBand) {
    judge_band(n, window_s);
    return;
  }
  // Far from the baseline's duties the valves' dead times change every nozzle's flow per
  // commanded second alike: neither a nozzle's fault nor the slow common scale.
  const double base_duty =
      base_open_s_ / (static_cast<double>(config_.nozzles) * base_windows_ * window_s);
  // The period after a masked one too: its windows still hold the meter's and the hose's lag
  // of the masked pulses.
  if ((config_.duty_mask > 0.0 && std::abs(recent_duty - base_duty) > config_.duty_mask) ||
      short_pulse) {
    masked_windows_left_ = config_.nozzles;
    return;
  }
  if (masked_windows_left_ > 0) {
    --masked_windows_left_;
    return;
  }
  double predicted = 0.0;
  for (std::size_t i = 0; i < n; ++i) predicted += open_s[i] * baseline_[i];
  double residual = metered_l - predicted;
  // The common scale of all nozzles (forgotten least squares of the residual on the prediction)
  // is no single nozzle's fault.
  const double common_keep = std::exp(-window_s / config_.common_time_constant_s);
  common_num_ = common_keep * common_num_ + predicted * residual;
  common_den_ = common_keep * common_den_ + predicted * predicted;
  if (common_den_ > 0.0) residual -= predicted * common_num_ / common_den_;
  int best = -1;
  double best_g = 0.0, second_g = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(baseline_[i] > 0.0)) continue;  // never seen open in the baseline: nothing to judge
    const double theta = config_.alarm_fraction * baseline_[i];  // the change looked for [L/s]
    const double signal = theta * open_s[i] * residual;
    const double drift = 0.5 * theta * theta * open_s[i] * open_s[i];
    cusum_down_[i] = std::max(0.0, cusum_down_[i] + (-signal - drift) / noise_var_);
    cusum_up_[i] = std::max(0.0, cusum_up_[i] + (signal - drift) / noise_var_);
    const double g = std::max(cusum_down_[i], cusum_up_[i]);
    if (g > best_g) {
      second_g = best_g;
      best_g = g;
      best = static_cast<int>(i);
    } else if (g > second_g) {
      second_g = g;
    }
  }
  // Neighbours' regressors overlap, so a fault also raises the others' evidence for a while;
  // the named one must explain the windows clearly better than the runner-up.
  if (alarmed_ < 0 && best_g > config_.alarm_threshold &&
      best_g - second_g > config_.isolation_margin) {
    alarmed_ = best;
    const auto k = static_cast<std::size_t>(best);
    alarmed_low_ = cusum_down_[k] >= cusum_up_[k];
  }
}

void NozzleHealth::judge_band(std::size_t n, double window_s) noexcept {
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
    if (outside_s_ >= config_.alarm_hold_s) {
      alarmed_ = worst;
      const auto k = static_cast<std::size_t>(worst);
      alarmed_low_ = current_[k] < baseline_[k];
    }
  } else {
    outside_s_ = 0.0;
    candidate_ = -1;
  }
}

double NozzleHealth::evidence(std::size_t nozzle) const noexcept {
  if (nozzle >= config_.nozzles) return 0.0;
  return std::max(cusum_down_[nozzle], cusum_up_[nozzle]);
}

double NozzleHealth::ratio(std::size_t nozzle) const noexcept {
  if (!baseline_ready_ || nozzle >= config_.nozzles || !(baseline_[nozzle] > 0.0)) return 1.0;
  return current_[nozzle] / baseline_[nozzle];
}

}  // namespace weedspray::control
