// SPDX-License-Identifier: Apache-2.0
// Flow trim (SPEC §3/§4) and calibration drift: what the line flow meter says about the
// calibrated nozzle lines. Both read windows of the meter's volume against what the lines
// promise at the duties actually commanded (after the trim; FlowTrimWindows) and keep the
// ratio "metered over promised" as a ratio of exponentially forgotten sums (CalibrationRatio):
// - FlowTrim, fast (10 s): correction = 1 / ratio, bounded, applied to the PWM-modulated
//   nozzles' flows (trimmed_duty_pct); closed and held-open valves cannot be trimmed.
// - CalibrationRatio itself, slow (60 s): the daemon's calibration_drift warning.
// Why a ratio, and not an integrator that drives the metered total to the requested total:
// the meter sees only the boom's sum, so the trim can correct only what
// every nozzle shares (a meter or fluid change, the pump, common wear). The integrator also put
// the error of the nozzles it cannot move (held open, clamped at the law's minimum duty) on the
// modulated ones, amplified by total / modulated share: with three worn nozzles held open, the
// one modulated nozzle took all of their excess. The ratio corrects each modulated nozzle by the
// boom's common change and leaves a held-open nozzle's own error where it is (the two compared
// on drawn machines: `weedspray-lab experiment orthogonal --plants 20`, docs/benchmarks.md).
// Windows are unusable (the ratio and the trim hold) when too little flow is promised, the
// valves are mostly closed, a nozzle held open has no measured full-open flow
// (FlowTrimInput::promise_known), or the pressure was off its set-point during the window:
// there the meter says nothing about the lines. Units: flow L/min, time s. Pure;
// allocation-free.
#pragma once

#include <cstdint>

#include "control/spray_rate_law.hpp"

namespace weedspray::control {

struct FlowTrimConfig {
  double min_correction = 0.7;
  double max_correction = 1.3;
  // The trim's ratio forgets with this time constant: ten 1 s windows, so a changed boom is
  // followed within a run of the L16 test while one odd window moves it by a tenth of its error.
  // The L16's figures barely move between 2 and 10 s; the blockage detector's does: a trim that
  // follows the boom quickly takes part of a blocked nozzle's deficit out before the detector
  // names it (`experiment blockage --plants 20`, named within 10 s, seeds 1 / 2 / 3: 5 s 19 / 20
  // / 20 of 20, 10 s 20 / 20 / 20, 20 s 19 of 20 on seed 1).
  double time_constant_s = 10.0;
  double min_observed_s = 2.0;  // seconds of usable windows before the correction leaves 1
  // Window rules, shared with CalibrationRatio:
  double min_requested_flow_l_per_min = 0.05;  // promised flow below: unusable
  double min_open_fraction = 0.1;              // mean valve open fraction below: unusable
  // Worst |P - P_set| / P_set seen during the window above this: unusable.
  double max_pressure_error_fraction = 0.05;
};

// One measurement window.
struct FlowTrimInput {
  // What the calibrated lines promise at the commanded duties (time mean over the window).
  double promised_l_per_min = 0.0;
  double measured_total_l_per_min = 0.0;  // flow meter over the window
  double open_fraction = 0.0;             // mean commanded duty of all valves, 0..1
  // Worst |P - P_set| / P_set over the window (0 if unknown / held).
  double pressure_error_fraction = 0.0;
  double dt_s = 0.0;  // window length
  // False when, at some tick of the window, a nozzle was held open whose full-open flow no
  // calibration measured: its promise was then the line extrapolated to 100 %, which is not
  // what an open valve sprays (on the simulated machine held-open nozzles sprayed ~15 % more
  // by volume), and the ratio would take that for the boom's change. The window is unusable.
  bool promise_known = true;
};

// The line meter's volume over what the calibrated lines promised at the duties commanded,
// both summed with exponential forgetting over usable windows (1 = as calibrated). Pure;
// allocation-free.
class CalibrationRatio {
 public:
  // time_constant_s: the exponential average's; known after min_observed_s of usable windows.
  // Throws std::invalid_argument naming the argument.
  explicit CalibrationRatio(const FlowTrimConfig& window_rules, double time_constant_s = 60.0,
                            double min_observed_s = 30.0);
  void update(const FlowTrimInput& window) noexcept;
  bool known() const noexcept { return observed_s_ > 0.0 && observed_s_ >= min_observed_s_; }
  // Metered over promised volume (1 = as calibrated), 1 until known.
  double ratio() const noexcept { return known() ? metered_ / promised_ : 1.0; }
  void reset() noexcept { observed_s_ = metered_ = promised_ = 0.0; }

 private:
  FlowTrimConfig window_rules_;
  double time_constant_s_;
  double min_observed_s_;
  double observed_s_ = 0.0;
  // Exponentially forgotten volumes (a ratio of sums: no window, the first included, weighs
  // more than its volume).
  double metered_ = 0.0;
  double promised_ = 0.0;
};

class FlowTrim {
 public:
  // Throws std::invalid_argument naming the field.
  explicit FlowTrim(const FlowTrimConfig& config);

  // One window (promise at the commanded duties); returns the correction to apply.
  double update(const FlowTrimInput& window) noexcept;
  // 1 / the ratio, within [min_correction, max_correction]; 1 until the ratio is known.
  double correction() const noexcept;
  // The last window was unusable (or none came yet): the correction holds.
  bool frozen() const noexcept { return frozen_; }
  void reset() noexcept {
    ratio_.reset();
    frozen_ = true;
  }

 private:
  FlowTrimConfig config_;
  CalibrationRatio ratio_;
  bool frozen_ = true;
};

// What the calibrated line promises a nozzle at a duty (the trim's reference, taken at the
// commanded duties). Closed: 0; held open: the full-open flow at the pressure
// (held_open_flow_l_per_min); between: its line.
double promised_flow_l_per_min(const NozzleLine& line, double duty_pct,
                               double pressure_mpa) noexcept;

// The duty that makes a modulated nozzle (0 < duty < 100) spray `correction` x what its line
// promises at duty_pct: the trim scales each nozzle's FLOW, not its duty. Scaling duties would
// move a low-duty nozzle's flow by less than a high-duty one's (the line's intercept), so
// nozzles sprayed at different rates would not keep their ratio. Closed and held-open duties are
// returned as they are; the result is not clamped (the caller's law owns its band).
double trimmed_duty_pct(const NozzleLine& line, double duty_pct, double correction,
                        double pressure_mpa) noexcept;

// One control tick as the trim sees it.
struct FlowTrimTick {
  double promised_l_per_min = 0.0;       // summed over the nozzles, at the commanded duties
  double open_fraction = 0.0;            // mean commanded duty of all valves, 0..1
  double pressure_error_fraction = 0.0;  // |P - P_set| / P_set now
  std::uint64_t pulses = 0;              // the meter's running count
  bool promise_known = true;             // see FlowTrimInput::promise_known
};

// Cuts the control loop's ticks into FlowTrim windows against the meter's pulse count: the
// daemon's sprayer and the lab's rig both feed FlowTrim through this, so the lab's figures for
// the trim are the daemon's. Over a window the promised flow and the open fraction are time
// means, the pressure error is the worst tick's, and the measured flow is the
// pulses counted over the window's length (a whole number of ticks: at a whole-Hz PWM frequency
// a 1 s window holds whole periods of every valve, which a window shorter than a period does not).
// Allocation-free.
class FlowTrimWindows {
 public:
  explicit FlowTrimWindows(double window_s = 1.0) : window_s_(window_s) {}
  // One tick of dt [s] (ticks after the window's start). The first tick after construction or
  // reset() only starts a window. True when a window closed: then `out` holds it.
  bool tick(double dt_s, const FlowTrimTick& tick, double pulses_per_litre,
            FlowTrimInput& out) noexcept;
  // Not spraying, or the duties not the law's (a calibration): the next tick starts afresh.
  void reset() noexcept { started_ = false; }
  double window_s() const noexcept { return window_s_; }

 private:
  double window_s_;
  bool started_ = false;
  std::uint64_t start_pulses_ = 0;
  double elapsed_s_ = 0.0;
  FlowTrimInput sums_{};  // time integrals (flows, open fraction) and the worst pressure error
};

}  // namespace weedspray::control
