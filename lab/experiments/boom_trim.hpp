// SPDX-License-Identifier: Apache-2.0
// Boom trim as a model: the line flow meter against what the calibrated lines promise. LAB ONLY
// (`weedspray-lab experiment orthogonal --plants N`, row "model"): the daemon's FlowTrim
// (flow_feedback.hpp) is the gain term of this model alone, 1 / (metered over promised). Both
// leave a held-open nozzle's own error where it is, where an
// integral law puts it on the modulated ones. With the valve-timing term this model is
// better on the changed machine's worst max (7.80 against 9.25 %), but on a sparse variable-rate
// field (`experiment savings --plants 20`) it under-doses: 20.8 % of nozzle-zones below target
// against 9.1-9.6 % with the daemon's trims. Valves switching all the time bias the meter's
// windows (below), and a model fitted to each window takes that for the boom's valve timing.
//
// Model of what the boom delivers after its calibration, per window:
//   V = k P + D S + e
// P: the volume the calibrated lines promised at the duties latched (full-open flow for a
// valve held open) [L]; S: the lines' slope dL/dd x the time each nozzle was modulated,
// summed [L per % duty]; k: the boom's common flow change (wear, meter drift, pump and
// pressure drift since calibration: the same at every duty); D [% duty]: the valves' common
// timing change (an aged valve that closes later sprays a fixed extra time per pulse, a large
// share at low duty and none when held open). Both enter linearly; a Kalman filter estimates
// them (priors k = 1 +- prior_gain_sd, D = 0 +- prior_offset_sd, a slow random walk,
// measurement noise learned from the innovations). With one mix of duties only k P + D S is
// seen; the prior shares it between k and D, and as the mix changes they come apart.
//
// The rate law would then ask each modulated nozzle's line for (request - a D) / k (a: slope);
// a nozzle held open is not moved (its flow does not follow the line near 100 %: the
// off-pulse is shorter than the valve's closing delay).
//
// Why not one trim per nozzle, from the staggered phase windows the health detector reads:
// tried (probes on the lab's machines, not commands). The meter sits at the
// manifold behind the feed hose's inertance and the boom's compliance, and the valves move
// 15-40 ms after their command, so which window a pulse's volume lands in depends on timing the
// controller does not know: on seed 1's first machine as made, the per-nozzle gains came out
// 0.80-1.26 instead of ~1, and moved by 5-10 % with 20 ms of assumed meter lag. From whole 1 s
// windows, a gain and an offset per nozzle with the state carried over the L16's 16 mixes, the
// model's mix-dependent errors (pressure lost along the boom, the meter's low-flow error) were
// taken for nozzle changes: on that machine as made 1.89 % mean error against 0.74 % for a
// common trim, and on 6 changed machines 2.80 % mean / 8.5 % max against FlowTrim's (then an
// integrator) 2.24 / 7.1.
//
// Pure (no clocks, threads or I/O), fixed-size state, allocation-free.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace weedspray::lab::experiments {

struct BoomTrimConfig {
  double prior_gain_sd = 0.05;   // k's sd as calibrated (wear, meter and pump drift since)
  double prior_offset_sd = 2.0;  // D's sd [% duty] (valve ageing: +3 ms at 3-10 Hz PWM)
  // Random walk per sqrt(s) of spraying: lets the estimate follow slow wear and drift.
  double gain_drift_per_sqrt_s = 0.001;
  double offset_drift_per_sqrt_s = 0.02;
  double min_gain = 0.7;  // the estimate is clamped to these (a larger change is a fault,
  double max_gain = 1.3;  // not something to trim)
  double max_offset_pct = 10.0;
  // Forgetting of the learned measurement noise [s], and its floor as a fraction of the
  // window's promised volume.
  double noise_time_constant_s = 30.0;
  double min_noise_fraction = 0.003;
};

// Throws std::invalid_argument naming the field.
void validate(const BoomTrimConfig& config);

// One window of the meter.
struct BoomTrimWindow {
  double promised_l = 0.0;       // P
  double slope_l_per_pct = 0.0;  // S
  double metered_l = 0.0;        // V
  double window_s = 0.0;
};

class BoomTrim {
 public:
  explicit BoomTrim(const BoomTrimConfig& config);

  // Windows with nothing promised only let the estimate drift; non-finite or negative input
  // is ignored. Allocation-free.
  void add_window(const BoomTrimWindow& window) noexcept;

  double gain() const noexcept { return theta_[0]; }        // k
  double offset_pct() const noexcept { return theta_[1]; }  // D
  // The flow to ask a modulated nozzle's line for so that it delivers request [L/min]
  // (slope: its line's dL/dd at the current pressure, L/min per % duty).
  double flow_to_ask(double request_l_per_min, double slope_l_per_min_per_pct) const noexcept;
  std::size_t windows() const noexcept { return windows_; }
  void reset() noexcept;

 private:
  BoomTrimConfig config_;
  std::array<double, 2> theta_{1.0, 0.0};
  std::array<std::array<double, 2>, 2> cov_{};
  double noise_var_ = 0.0;  // learned relative per-window noise, (fraction of P)^2
  std::size_t windows_ = 0;
};

// Cuts the control loop's ticks into BoomTrim windows against the meter's pulse count. A
// window is dropped whole when any tick in it was not usable (not spraying, pressure off its
// set-point: the lines' promise holds at the set-point only) or when the promised flow moved
// by more than max_promise_change of its largest value in it: valves opening or closing
// together start a transient of the feed hose, whose inertia and the boom's compliance keep
// the meter's flow behind the nozzles' for a few tenths of a second (a run starting from
// closed valves read 5 % low in its first windows and the trim took it for the valves).
// Allocation-free.
class BoomTrimWindows {
 public:
  explicit BoomTrimWindows(double window_s = 1.0, double max_promise_change = 0.2)
      : window_s_(window_s), max_promise_change_(max_promise_change) {}
  // One tick of dt [s]: the flow the lines promised at the latched duties [L/min] and their
  // slopes summed over the modulated nozzles [L/min per % duty]; pulses: the meter's running
  // count. True when a usable window closed: then `out` holds it.
  bool tick(double dt_s, double promised_l_per_min, double slope_l_per_min_per_pct, bool usable,
            std::uint64_t pulses, double pulses_per_litre, BoomTrimWindow& out) noexcept;
  void reset() noexcept { started_ = false; }

 private:
  double window_s_;
  double max_promise_change_;
  bool started_ = false;
  std::uint64_t start_pulses_ = 0;
  double min_promise_ = 0.0;
  double max_promise_ = 0.0;
  BoomTrimWindow current_{};
};

}  // namespace weedspray::lab::experiments
