// Flow trim (SPEC §3/§4): a slow, bounded, rate-limited integrator that makes the measured
// total flow (pulse meter) match the sum of the nozzle flows the spray-rate law asked for.
// Output: a multiplicative correction applied to all duties (duty' = duty * correction).
// correction += gain * (requested - measured) / requested * dt, the step limited to
// max_rate_per_s * dt and the value to [min_correction, max_correction].
// Frozen (held) when too little flow is requested or the valves are mostly closed — there the
// meter reading means nothing. Units: flow L/min, dt s. Pure; update() allocation-free.
#pragma once

namespace weedspray::control {

struct FlowTrimConfig {
  double min_correction = 0.7;
  double max_correction = 1.3;
  double gain_per_s = 0.2;                     // correction per second per unit relative error
  double max_rate_per_s = 0.05;                // |d correction / dt| limit
  double min_requested_flow_l_per_min = 0.05;  // below: frozen
  double min_open_fraction = 0.1;              // mean valve open fraction below: frozen
};

class FlowTrim {
 public:
  // Throws std::invalid_argument naming the field.
  explicit FlowTrim(const FlowTrimConfig& config);

  // open_fraction: mean commanded duty of all valves as a fraction 0..1.
  // Returns the correction to apply. Non-finite inputs or dt <= 0 freeze the trim.
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
