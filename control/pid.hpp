// SPDX-License-Identifier: Apache-2.0
// PID controller for the line-pressure loop (SPEC §4; LinuxCNC pid.c habits).
//
// - Derivative on the measurement (a set-point step does not kick the output), with an
//   optional first-order low-pass filter on the derivative term.
// - Output clamped to [output_min, output_max]; integrator anti-windup by conditional
//   clamping (stop integrating while saturated in the error's direction) or back-calculation.
// - The integrator is stored as its contribution to the output (sum of Ki e dt), so changing
//   gains between cycles does not bump the output through the integral.
// - Bumpless enable: the integrator is preset so that the first output equals the output the
//   actuator currently has.
// Units: whatever the caller uses for set-point/measurement (e.g. MPa) and output (e.g. DAC
// fraction 0..1); dt in seconds. Pure: no clocks, no allocation, update() is noexcept.
#pragma once

namespace weedspray::control {

struct PidGains {
  double kp = 0.0;  // output units per error unit
  double ki = 0.0;  // output units per (error unit * s)
  double kd = 0.0;  // output units per (error unit / s)
};

enum class AntiWindup {
  kClamping,         // conditional integration: freeze while saturated and error pushes further
  kBackCalculation,  // integrator bled back by tracking_gain * (saturated - unsaturated output)
};

struct PidConfig {
  PidGains gains{};
  double output_min = 0.0;
  double output_max = 1.0;
  AntiWindup anti_windup = AntiWindup::kClamping;
  double tracking_gain_per_s = 10.0;  // back-calculation gain Kt [1/s]
  double derivative_filter_s = 0.0;   // time constant of the derivative low-pass, 0 = none
};

// Per-term breakdown of the last update, for logs and tests.
struct PidTerms {
  double proportional = 0.0;
  double integral = 0.0;
  double derivative = 0.0;
  double unsaturated_output = 0.0;
  double output = 0.0;
};

class Pid {
 public:
  // Throws std::invalid_argument naming the field when the config is unusable
  // (output_min >= output_max, negative time constants, non-finite values).
  explicit Pid(const PidConfig& config);

  // One control cycle. dt_s <= 0 or non-finite inputs: the last output is returned unchanged.
  // While disabled, only the measurement is tracked and the last output is returned.
  double update(double setpoint, double measurement, double dt_s) noexcept;

  // Gains may change between cycles; the integral contribution is kept as is (no bump).
  void set_gains(const PidGains& gains) noexcept { config_.gains = gains; }
  const PidGains& gains() const noexcept { return config_.gains; }
  const PidConfig& config() const noexcept { return config_; }

  // Bumpless transfer: preset the integrator so the next output (for this set-point and
  // measurement, derivative zero) equals current_output (clamped to the output range).
  void enable(double current_output, double setpoint, double measurement) noexcept;
  void disable() noexcept { enabled_ = false; }
  bool enabled() const noexcept { return enabled_; }

  // Zero the integrator and forget the previous measurement; the output becomes 0 clamped
  // into [output_min, output_max]. Keeps the enabled state.
  void reset() noexcept;

  double output() const noexcept { return terms_.output; }
  const PidTerms& last_terms() const noexcept { return terms_; }

 private:
  PidConfig config_;
  bool enabled_ = true;
  bool has_previous_ = false;
  double previous_measurement_ = 0.0;
  double integral_ = 0.0;
  double filtered_derivative_ = 0.0;
  PidTerms terms_{};
};

}  // namespace weedspray::control
