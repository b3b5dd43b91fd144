// Per-nozzle health from the ONE line flow meter while spraying (issue 12).
//
// With staggered PWM phases the nozzles are open in different parts of each period, so the
// meter's volume per phase window is a different mix of nozzles in each window:
//   V(w) = sum_i open_s(i, w) c_i + noise,
// with c_i nozzle i's flow while open [L/s]. (Synchronous PWM opens all of them together: the
// windows are all the same mix and the c_i cannot be told apart.) The detector solves this by
// exponentially forgetting least squares (time constant time_constant_s) and compares each c_i
// with its own baseline, learned over the first baseline_s of spraying (the nozzles as they
// were when the job started or after a clean). A nozzle whose ratio stays outside
// [1 - alarm_fraction, 1 + alarm_fraction] for alarm_hold_s is named (blocked: below, worn or
// valve stuck open: above). The online flow trim scales every duty alike, so it changes the
// open times this detector is fed, not the c_i: it cannot hide one nozzle's fault.
//
// Pure (no clocks, threads or I/O), fixed-size state: no allocation after construction.
#pragma once

#include <array>
#include <cstddef>
#include <span>

namespace weedspray::control {

inline constexpr std::size_t kMaxHealthNozzles = 8;

struct NozzleHealthConfig {
  std::size_t nozzles = 4;
  double baseline_s = 60.0;      // spraying time the baselines are learned over
  double time_constant_s = 6.0;  // forgetting of the running estimate
  double alarm_fraction = 0.12;  // |c / baseline - 1| above this is a fault...
  double alarm_hold_s = 1.0;     // ...once it lasted this long
  double min_open_s = 0.5;       // a nozzle open less than this (weighted) is not judged
};

// Throws std::invalid_argument naming the field.
void validate(const NozzleHealthConfig& config);

class NozzleHealth {
 public:
  explicit NozzleHealth(const NozzleHealthConfig& config);

  // One phase window: each nozzle's commanded open time in it [s], the metered volume [L] and
  // the window's length [s]. Allocation-free.
  void add_window(std::span<const double> open_s, double metered_l, double window_s) noexcept;

  bool baseline_ready() const noexcept { return baseline_ready_; }
  // Current flow while open / baseline (1 = as at the start); 1 until the baseline is ready.
  double ratio(std::size_t nozzle) const noexcept;
  // The nozzle in alarm (the one furthest from its baseline), or -1.
  int alarmed_nozzle() const noexcept { return alarmed_; }
  void reset() noexcept;

 private:
  using Vector = std::array<double, kMaxHealthNozzles>;
  using Matrix = std::array<Vector, kMaxHealthNozzles>;
  // Solves s x = b (Gaussian elimination, partial pivoting); false if singular.
  bool solve(const Matrix& s, const Vector& b, Vector& x) const noexcept;

  NozzleHealthConfig config_;
  Matrix base_s_{};
  Vector base_b_{};
  Matrix run_s_{};
  Vector run_b_{};
  Vector open_weight_{};  // forgotten open time per nozzle (judgeable?)
  Vector baseline_{};
  Vector current_{};
  double sprayed_s_ = 0.0;
  bool baseline_ready_ = false;
  double outside_s_ = 0.0;
  int candidate_ = -1;
  int alarmed_ = -1;
};

}  // namespace weedspray::control
