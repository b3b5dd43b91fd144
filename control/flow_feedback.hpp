// Flow trim (SPEC §3/§4): a slow, bounded, rate-limited integrator that makes the measured
// total flow (pulse meter) match the sum of the nozzle flows the spray-rate law asked for.
// Output: a multiplicative correction applied to the PWM-modulated duties only
// (duty' = duty * correction for 0 < duty < 100; closed and fully open valves cannot be
// trimmed). Only the modulated nozzles' share of the request can move, so the error is
// normalised by that share:
//   correction += gain * (requested - measured) / trimmable * dt,
// the step limited to max_rate_per_s * dt and the value to [min_correction, max_correction].
// (Normalising by the whole request would dilute the error by the nozzles held at 100 %: a
// trim wound up during a transient then takes minutes to unwind.)
// Frozen (held) when too little flow is requested or trimmable, the valves are mostly closed,
// a nozzle held open has no measured full-open flow (FlowTrimInput::promise_known),
// the modulated share is too small to observe (min_trimmable_fraction), or the pressure was off
// its set-point during the measurement window — there the meter
// reading says nothing about the duties. Units: flow L/min, dt s. Pure; allocation-free.
#pragma once

#include <cstdint>

#include "control/spray_rate_law.hpp"

namespace weedspray::control {

struct FlowTrimConfig {
  double min_correction = 0.7;
  double max_correction = 1.3;
  double gain_per_s = 0.2;                     // correction per second per unit relative error
  double max_rate_per_s = 0.05;                // |d correction / dt| limit
  double min_requested_flow_l_per_min = 0.05;  // below: frozen
  double min_open_fraction = 0.1;              // mean valve open fraction below: frozen
  // Trimmable share of the request below this: frozen. The meter sees only the total, so a
  // small modulated share cannot be told apart from the fixed nozzles' model error (which the
  // normalised error would amplify by total / trimmable).
  double min_trimmable_fraction = 0.3;
  // Worst |P - P_set| / P_set seen during the window above this: frozen.
  double max_pressure_error_fraction = 0.05;
};

// One measurement window.
struct FlowTrimInput {
  double requested_total_l_per_min = 0.0;  // all nozzles the law asked to spray
  // The part of the request delivered by PWM-modulated nozzles (0 < duty < 100).
  double trimmable_l_per_min = 0.0;
  double measured_total_l_per_min = 0.0;  // flow meter over the window
  double open_fraction = 0.0;             // mean commanded duty of all valves, 0..1
  // Worst |P - P_set| / P_set over the window (0 if unknown / held).
  double pressure_error_fraction = 0.0;
  double dt_s = 0.0;  // window length
  // False when, at some tick of the window, a nozzle was held open whose full-open flow no
  // calibration measured: its promise was then the line extrapolated to 100 %, which is not
  // what an open valve sprays (on the simulated machine held-open nozzles sprayed ~15 % more
  // by volume), and the trim would take that out of the modulated nozzles. Freezes the trim.
  bool promise_known = true;
};

class FlowTrim {
 public:
  // Throws std::invalid_argument naming the field.
  explicit FlowTrim(const FlowTrimConfig& config);

  // Returns the correction to apply. Non-finite inputs or dt <= 0 freeze the trim.
  double update(const FlowTrimInput& input) noexcept;
  // Older form: every requested nozzle treated as trimmable, pressure assumed on set-point.
  double update(double requested_total_l_per_min, double measured_total_l_per_min,
                double open_fraction, double dt_s) noexcept;

  double correction() const noexcept { return correction_; }
  bool frozen() const noexcept { return frozen_; }
  void reset() noexcept {
    correction_ = 1.0;
    frozen_ = true;
  }

 private:
  FlowTrimConfig config_;
  double correction_ = 1.0;
  bool frozen_ = true;
};

// What the law promises a nozzle at the duty it chose: the trim's reference. Closed: 0; held
// open: the full-open flow at the pressure (held_open_flow_l_per_min); between: its line.
double promised_flow_l_per_min(const NozzleLine& line, double duty_pct,
                               double pressure_mpa) noexcept;

// The duty that makes a modulated nozzle (0 < duty < 100) spray `correction` x what its line
// promises at duty_pct: the trim scales each nozzle's FLOW, not its duty. Scaling duties would
// move a low-duty nozzle's flow by less than a high-duty one's (the line's intercept), so
// nozzles sprayed at different rates would not keep their ratio, and the trim's error, which is
// normalised by the modulated nozzles' flow, would not be what one step of it moves. Closed
// and held-open duties are returned as they are; the result is not clamped (the caller's law
// owns its band).
double trimmed_duty_pct(const NozzleLine& line, double duty_pct, double correction,
                        double pressure_mpa) noexcept;

// One control tick as the trim sees it.
struct FlowTrimTick {
  double promised_l_per_min = 0.0;       // summed over the nozzles, at the law's duties
  double trimmable_l_per_min = 0.0;      // of that, the modulated nozzles' share
  double open_fraction = 0.0;            // mean commanded duty of all valves, 0..1
  double pressure_error_fraction = 0.0;  // |P - P_set| / P_set now
  std::uint64_t pulses = 0;              // the meter's running count
  bool promise_known = true;             // see FlowTrimInput::promise_known
};

// Cuts the control loop's ticks into FlowTrim windows against the meter's pulse count: the
// daemon's sprayer and the lab's rig both feed FlowTrim through this, so the lab's figures for
// the trim are the daemon's. Over a window the promised and trimmable flows and the open
// fraction are time means, the pressure error is the worst tick's, and the measured flow is the
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

// How far the boom sprays from its calibration, for the daemon's calibration_drift warning:
// the line meter's volume over what the calibrated lines promise at the duties actually
// commanded (after the trim), both summed with exponential forgetting over usable windows
// (FlowTrim's freeze rules for flow, open valves and pressure; no modulated share needed).
// FlowTrim's correction is not this: its integral law drives the total and so puts the error of
// nozzles it cannot move (held open, or clamped at the law's minimum duty) on the modulated
// ones (the daemon's sim, 1 m/s, meter 10 % high: the trim at 0.73-0.74 where 1/1.1 = 0.91,
// this ratio 1.06 and rising). Feed it windows from a
// FlowTrimWindows whose promised flow is taken at the commanded duties. Pure; allocation-free.
class CalibrationRatio {
 public:
  // time_constant_s: the exponential average's; known after min_observed_s of usable windows.
  explicit CalibrationRatio(const FlowTrimConfig& freeze_rules, double time_constant_s = 60.0,
                            double min_observed_s = 30.0);
  void update(const FlowTrimInput& window) noexcept;
  bool known() const noexcept { return observed_s_ >= min_observed_s_; }
  // Metered over promised volume (1 = as calibrated), 1 until known.
  double ratio() const noexcept { return known() ? metered_ / promised_ : 1.0; }
  void reset() noexcept { observed_s_ = metered_ = promised_ = 0.0; }

 private:
  FlowTrimConfig freeze_rules_;
  double time_constant_s_;
  double min_observed_s_;
  double observed_s_ = 0.0;
  // Exponentially forgotten volumes (a ratio of sums: no window, the first included, weighs
  // more than its volume).
  double metered_ = 0.0;
  double promised_ = 0.0;
};

}  // namespace weedspray::control
