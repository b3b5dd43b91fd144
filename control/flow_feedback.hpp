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
// the modulated share is too small to observe (min_trimmable_fraction), or the pressure was off
// its set-point during the measurement window — there the meter
// reading says nothing about the duties. Units: flow L/min, dt s. Pure; allocation-free.
#pragma once

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

}  // namespace weedspray::control
