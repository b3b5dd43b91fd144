// SPDX-License-Identifier: Apache-2.0
// What the ONE line flow meter tells about each nozzle's flow in one fixed-duty run:
// a lab diagnostic, not a controller.
//
// With staggered PWM phases each phase window's metered volume is a different mix of nozzles
// (control/nozzle_health.hpp):
//   V(w) = sum_i e_i(w) r_i + noise,
// e_i(w) the volume nozzle i's calibrated line promises in window w, r_i its metered / promised
// ratio. The rig (closed_loop_rig.hpp, identify_nozzles) counts e_i(w) as the time the valve
// flows in the window by its label timing (the commanded pulse moved by the mean open and close
// lags) x the line's flow per flowing second at the latched duty.
// The r_i are the least-squares fit over the run; where the mix does not tell nozzles apart
// (several held open together) a small ridge pulls them to the common ratio (ratio of sums,
// what FlowTrim uses). A per-nozzle trim would be fed these r_i, so their error against each
// nozzle's true ratio says how well such a trim could correct it (README, experiment
// orthogonal).
//
// Pure, fixed-size state.
#pragma once

#include <array>
#include <cstddef>
#include <span>

namespace weedspray::lab::experiments {

class PhaseWindowFit {
 public:
  static constexpr std::size_t kMaxNozzles = 8;
  // Throws std::invalid_argument unless nozzles is in [1, 8] and ridge > 0.
  explicit PhaseWindowFit(std::size_t nozzles, double ridge = 1e-3);

  // One phase window: each nozzle's promised volume in it [L] and the metered volume [L].
  void add_window(std::span<const double> promised_l, double metered_l) noexcept;
  // The fitted metered / promised ratio of each nozzle (1 before any window).
  double ratio(std::size_t nozzle) const noexcept;
  double common_ratio() const noexcept;
  void reset() noexcept;

 private:
  using Vector = std::array<double, kMaxNozzles>;
  using Matrix = std::array<Vector, kMaxNozzles>;
  std::size_t nozzles_;
  double ridge_;
  Matrix s_{};  // sum of e e^T
  Vector b_{};  // sum of e V
  double promised_sum_ = 0.0;
  double metered_sum_ = 0.0;
};

}  // namespace weedspray::lab::experiments
