// SPDX-License-Identifier: Apache-2.0
// Solves the small dense systems of the per-nozzle fits (nozzle health, the lab's phase-window
// fit): at most 8 unknowns, on fixed-size arrays, so it can run on the real-time path without
// allocation. Hand-written because of that: Eigen is not a dependency of the control library.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <utility>

namespace weedspray::control {

// Solves a x = y for the first n rows and columns (Gaussian elimination with partial
// pivoting). Returns false, leaving x as it was, when a pivot is below 1e-12 (singular).
template <std::size_t N>
bool solve_small_system(std::array<std::array<double, N>, N> a, std::array<double, N> y,
                        std::size_t n, std::array<double, N>& x) noexcept {
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
  std::array<double, N> solved{};
  for (std::size_t i = n; i-- > 0;) {
    double v = y[i];
    for (std::size_t k = i + 1; k < n; ++k) v -= a[i][k] * solved[k];
    solved[i] = v / a[i][i];
  }
  for (std::size_t i = 0; i < n; ++i) x[i] = solved[i];
  return true;
}

}  // namespace weedspray::control
