// SPDX-License-Identifier: Apache-2.0
// Per-nozzle health from the ONE line flow meter while spraying.
//
// With staggered PWM phases the nozzles are open in different parts of each period, so the
// meter's volume per phase window is a different mix of nozzles in each window:
//   V(w) = sum_i open_s(i, w) c_i + noise,
// with c_i nozzle i's flow while open [L/s]. (Synchronous PWM opens all of them together: the
// windows are all the same mix and the c_i cannot be told apart.) The baselines c0_i are a
// least-squares fit over the first baseline_s of spraying (the nozzles as they were when the
// job started or after a clean); the fit's residual variance s2 is this machine's noise per
// window (meter pulses, and the many small mismatches between commanded open times and the
// flow the meter sees).
//
// Two judges (NozzleJudge). kBand, the first: each nozzle's ratio() (below) outside
// [1 - alarm_fraction, 1 + alarm_fraction] for alarm_hold_s names it. Simple and tolerant of a
// common change of the whole line up to alarm_fraction, but the running fit scatters widely
// on a healthy machine, so the band must be wide and a blockage is named late.
//
// kCusum: a CUSUM per nozzle and direction on the residual against the baselines,
// r(w) = V(w) - sum_i open_s(i, w) c0_i: the log-likelihood ratio of "nozzle i's flow changed
// by -/+ alarm_fraction x c0_i" against "no change", summed over windows and floored at 0,
//   g_i <- max(0, g_i + (theta_i open_s(i, w) r(w) - theta_i^2 open_s(i, w)^2 / 2) / s2).
// The first g_i above alarm_threshold that beats every other nozzle's by isolation_margin names
// nozzle i (blocked: down, worn or valve stuck open: up); the margin because the nozzles'
// open times overlap, so one nozzle's fault raises its neighbours' evidence too for the first
// duty mixes. This holds the other nozzles at their baselines instead of re-estimating all of
// them every window: the running fit's scatter (anti-correlated between
// neighbours) is mostly a poorly conditioned duty mix, which this test does not see, and the
// evidence accumulates while the fault lasts instead of a band having to clear the scatter.
// A slow common scale of every nozzle (forgotten over common_time_constant_s) is taken out of
// the residual first, so that a slow drift of the whole line (meter, pressure) is not blamed on
// one nozzle; a sudden common step of a few % still is (relearn the baseline after changing the
// set-point). The model counts commanded open time, but the valves close later than they open:
// the flow per commanded second depends on the pulse width, so windows at duties far from the
// baseline's, or with short pulses, are not judged (duty_mask, min_pulse_s). The
// online flow trim scales every duty alike, so it changes the open times this
// detector is fed, not the c_i: it cannot hide one nozzle's fault.
//
// ratio(): each nozzle's flow from an exponentially forgetting least-squares fit of all of them
// (time_constant_s) over its baseline; what the band judges, for display with the CUSUM.
//
// Pure (no clocks, threads or I/O), fixed-size state: no allocation after construction.
#pragma once

#include <array>
#include <cstddef>
#include <span>

namespace weedspray::control {

inline constexpr std::size_t kMaxHealthNozzles = 8;

enum class NozzleJudge { kBand, kCusum };

struct NozzleHealthConfig {
  std::size_t nozzles = 4;
  NozzleJudge judge = NozzleJudge::kCusum;
  double baseline_s = 60.0;      // spraying time the baselines are learned over
  double time_constant_s = 6.0;  // forgetting of the running estimate (ratio())
  // Band: |ratio - 1| above this is a fault... CUSUM: the change of one nozzle's flow, as a
  // fraction of its baseline, looked for...
  double alarm_fraction = 0.12;
  double alarm_hold_s = 1.0;      // band: ...once it lasted this long
  double min_open_s = 0.5;        // band: a nozzle open less than this (weighted) is not judged
  double alarm_threshold = 24.0;  // CUSUM: ...named once its log-likelihood ratio exceeds this
  double isolation_margin = 6.0;  // CUSUM: the named nozzle's evidence over the runner-up's
  double common_time_constant_s = 20.0;  // CUSUM: forgetting of the common scale taken out
  // CUSUM: windows are not judged while the boom's mean duty (over one PWM period) is further
  // than duty_mask from the baseline's mean duty, or while an open nozzle's pulse (its duty
  // over one period x the period) is shorter than min_pulse_s (0: all judged). The valves
  // close later than they open (the simulator's plant: 11 ms per pulse) and take their travel
  // to open, so the flow per commanded open second depends on the pulse width: the baselines
  // hold near the duties they were learned at, a jump of every duty far from them looks like
  // every nozzle changing, and short pulses are mostly the valve's delays (README, experiment
  // blockage).
  double duty_mask = 0.2;
  double min_pulse_s = 0.04;
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
  // The nozzle in alarm, or -1 (band: the one furthest from its baseline; CUSUM: the first
  // whose evidence exceeded alarm_threshold, kept until reset()).
  int alarmed_nozzle() const noexcept { return alarmed_; }
  // Whether that nozzle's flow went down (blocked) rather than up (worn, valve stuck open). CUSUM:
  // the CUSUM that named it, not ratio(), which lags its alarm by a few seconds.
  bool alarmed_low() const noexcept { return alarmed_low_; }
  // CUSUM: the larger of the nozzle's two CUSUMs (down, up), its evidence of a change; 0 until
  // the baseline is ready, and with the band judge.
  double evidence(std::size_t nozzle) const noexcept;
  void reset() noexcept;

 private:
  using Vector = std::array<double, kMaxHealthNozzles>;
  using Matrix = std::array<Vector, kMaxHealthNozzles>;
  // Solves s x = b (Gaussian elimination, partial pivoting); false if singular.
  bool solve(const Matrix& s, const Vector& b, Vector& x) const noexcept;
  void judge_band(std::size_t n, double window_s) noexcept;

  NozzleHealthConfig config_;
  Matrix base_s_{};
  Vector base_b_{};
  Matrix run_s_{};
  Vector run_b_{};
  double base_vv_ = 0.0;  // sum of V^2 over the baseline (its residual variance)
  double base_windows_ = 0.0;
  double base_v_ = 0.0;  // sum of V over the baseline (the variance's floor)
  Vector baseline_{};
  Vector current_{};
  double noise_var_ = 0.0;   // s2: residual variance per window against the baselines
  double common_num_ = 0.0;  // forgotten sums for the common scale of the residual
  double common_den_ = 0.0;
  double base_open_s_ = 0.0;  // the baseline's open time of all nozzles (its mean duty)
  Matrix recent_open_{};      // the last period's windows (slot: window mod nozzles), open times
  std::size_t recent_slot_ = 0;
  std::size_t recent_windows_ = 0;       // windows in recent_open_ (up to nozzles)
  std::size_t masked_windows_left_ = 0;  // still not judged after a masked window
  Vector cusum_down_{};
  Vector cusum_up_{};
  Vector open_weight_{};  // band: forgotten open time per nozzle (judgeable?)
  double outside_s_ = 0.0;
  int candidate_ = -1;
  double sprayed_s_ = 0.0;
  bool baseline_ready_ = false;
  int alarmed_ = -1;
  bool alarmed_low_ = false;
};

}  // namespace weedspray::control
