// SPDX-License-Identifier: Apache-2.0
#include "lab/experiments/phase_window_fit.hpp"

#include "control/small_linear_system.hpp"
#include "lab/experiments/vocabulary.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace weedspray::lab::experiments {

PhaseWindowFit::PhaseWindowFit(std::size_t nozzles, double ridge)
    : nozzles_(nozzles), ridge_(ridge) {
  if (nozzles < 1 || nozzles > kMaxNozzles)
    throw std::invalid_argument("PhaseWindowFit: nozzles must be in [1, 8]");
  if (!(ridge > 0.0) || !std::isfinite(ridge))
    throw std::invalid_argument("PhaseWindowFit: ridge must be > 0");
}

void PhaseWindowFit::reset() noexcept {
  s_ = {};
  b_ = {};
  promised_sum_ = 0.0;
  metered_sum_ = 0.0;
}

void PhaseWindowFit::add_window(std::span<const double> promised_l, double metered_l) noexcept {
  const std::size_t n = std::min(nozzles_, promised_l.size());
  if (!std::isfinite(metered_l)) return;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(promised_l[i])) return;
    promised_sum_ += promised_l[i];
  }
  metered_sum_ += metered_l;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) s_[i][j] += promised_l[i] * promised_l[j];
    b_[i] += promised_l[i] * metered_l;
  }
}

double PhaseWindowFit::common_ratio() const noexcept {
  return promised_sum_ > 0.0 ? metered_sum_ / promised_sum_ : 1.0;
}

double PhaseWindowFit::ratio(std::size_t nozzle) const noexcept {
  if (nozzle >= nozzles_ || !(promised_sum_ > 0.0)) return 1.0;
  // (S + ridge D) r = b + ridge D common, D = diag(S) (a nozzle never open: r = common).
  const std::size_t n = nozzles_;
  const double common = common_ratio();
  Matrix a = s_;
  Vector y = b_;
  for (std::size_t i = 0; i < n; ++i) {
    if (s_[i][i] > 0.0) {
      a[i][i] += ridge_ * s_[i][i];
      y[i] += ridge_ * s_[i][i] * common;
    } else {
      a[i] = {};
      a[i][i] = 1.0;
      y[i] = common;
    }
  }
  Vector x{};
  x.fill(common);
  solve_small_system(a, y, n, x);  // positive definite: S + ridge diag(S), diag(S) > 0
  return x[nozzle];
}

}  // namespace weedspray::lab::experiments
