// SPDX-License-Identifier: Apache-2.0
// Spray-rate law: weed density -> nozzle flow -> valve duty (SPEC §2).
//
// Wheat paper (he2024), flows in L/min (the paper's "mL/min" only works in L/min):
//   nominal dose      u = q_nom / (60 w v_nom)             [L/m^2]
//   target flow       q = 60 D w v u / k                   [L/min]  (D density, k max density)
//   calibrated valve  q = A s + b  (s duty %, valid 20..80 %) -> s = (q - b) / A
//   clamp             s < min_duty -> 0 (closed), s > max_duty -> 100 (open)   (config)
//   low-duty policy   LowDutyPolicy::kClose is the SPEC clamp above. kRaiseToMin sprays every
//                     zone above the decision threshold at least at min_duty (the minimum
//                     effective dose): 0 < q and s < min_duty -> min_duty. A weed sprayer that
//                     leaves weedy zones dry is missing weeds, not saving liquid.
//   full open         q = A s + b stops holding near 100 %: once the off-time is shorter than
//                     the valve's closing delay the valve never closes and the nozzle gives its
//                     full-open flow. A calibrated line may carry that flow (metered at 100 %);
//                     a request at or above it then gets 100 % (valve held open), not a duty
//                     from the line.
// Pressure: nozzle flow scales with sqrt(P). The line was calibrated at P_cal, so at pressure
// P the line is q = (A s + b) sqrt(P / P_cal) and s = (q sqrt(P_cal / P) - b) / A. With b = 0
// this is exactly the SPEC's "duty times sqrt(P_cal / P)"; with b != 0 it is the exact form.
// 2018 paper (xu2018): a decision threshold on density below which nothing is sprayed; six
// density levels; and a nozzle-combination mode: three nozzles of different sizes per row,
// on/off, seven combinations, the one nearest the target flow is picked.
// Application rate R [L/ha] = 600 Q [L/min] / (v [km/h] w [m]) = 10000 Q / (60 v w) in SI.
// Units: speed m/s, width m, flow L/min, pressure MPa, duty %. Pure functions.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace weedspray::control {

// Calibrated flow-vs-duty line of one nozzle: q = slope * s + intercept at calibration pressure.
struct NozzleLine {
  double slope_l_per_min_per_pct = 0.00393;
  double intercept_l_per_min = 0.217;
  double calibration_pressure_mpa = 0.4;
  // Flow with the valve held open at calibration pressure; 0 = unknown (no full-open rule).
  double full_open_flow_l_per_min = 0.0;
};

enum class LowDutyPolicy {
  kClose,       // SPEC clamp: s < min_duty -> 0 (weedy zones below it stay dry)
  kRaiseToMin,  // equal coverage: a positive target flow gets at least min_duty
};

struct SprayLawConfig {
  double nominal_flow_l_per_min = 0.615;  // q_nom
  double nozzle_width_m = 0.5;            // w
  double nominal_speed_m_per_s = 1.0;     // v_nom
  double max_density = 1.0;               // k, density normaliser (0 < k <= 1)
  double decision_threshold = 0.0;        // density below this: nothing sprayed (2018 paper)
  double min_duty_pct = 20.0;             // below: closed
  double max_duty_pct = 80.0;             // above: fully open
  LowDutyPolicy low_duty_policy = LowDutyPolicy::kClose;
};

// Throws std::invalid_argument naming the field.
void validate(const SprayLawConfig& config);
void validate(const NozzleLine& line);

double nominal_dose_l_per_m2(const SprayLawConfig& config) noexcept;
// q = 60 D w v u / k; 0 below the decision threshold, density clamped to [0, k].
double target_flow_l_per_min(const SprayLawConfig& config, double density,
                             double speed_m_per_s) noexcept;
// Unclamped duty for a flow at pressure (pressure <= 0 or non-finite: no compensation).
// With a known full_open_flow_l_per_min F, a flow >= F min(1, sqrt(P / P_cal)) returns exactly
// 100 (the lower of the calibrated and the pressure-scaled full flow: below P_cal the valve
// cannot give more, above it set-point noise must not flip a full-flow valve into switching).
double raw_duty_for_flow_pct(const NozzleLine& line, double flow_l_per_min,
                             double pressure_mpa) noexcept;
// Applies the min/max clamp: < min -> 0, > max -> 100; flow <= 0 -> 0. (kClose semantics
// whatever the policy: the caller does not say whether anything is to be sprayed.)
double clamp_duty_pct(const SprayLawConfig& config, double raw_duty_pct) noexcept;
// The clamp with the configured low-duty policy, for a zone whose target flow is known:
// target <= 0 -> 0; kRaiseToMin lifts 0 < s < min_duty (and s <= 0 for a positive target)
// to min_duty.
double clamp_duty_for_flow_pct(const SprayLawConfig& config, double raw_duty_pct,
                               double target_flow_l_per_min) noexcept;
// Flow the line delivers at a duty and pressure (inverse of the above, for sims and logs).
double flow_for_duty_l_per_min(const NozzleLine& line, double duty_pct,
                               double pressure_mpa) noexcept;
// The line's slope dq/ds at a pressure [L/min per % duty] (what a duty offset is worth).
double line_slope_l_per_min_per_pct(const NozzleLine& line, double pressure_mpa) noexcept;
// The flow with the valve held open at a pressure: the calibrated full-open flow scaled by
// sqrt(P / P_cal), else (unknown) the line at 100 %.
double held_open_flow_l_per_min(const NozzleLine& line, double pressure_mpa) noexcept;

struct SprayDecision {
  double target_flow_l_per_min = 0.0;
  double raw_duty_pct = 0.0;  // before clamp
  double duty_pct = 0.0;      // after clamp (0, [min, max], or 100)
};

// The whole law for one nozzle zone (clamp_duty_for_flow_pct, so the policy applies).
SprayDecision spray_decision(const SprayLawConfig& config, const NozzleLine& line, double density,
                             double speed_m_per_s, double pressure_mpa) noexcept;

// Application rate from SI inputs; speed or width <= 0 gives 0.
double application_rate_l_per_ha(double flow_l_per_min, double speed_m_per_s,
                                 double width_m) noexcept;

// Quantise duty to a few levels with hysteresis: the output stays at its level while the input
// is within half a step plus `hysteresis_pct` of it; otherwise it jumps to the nearest level.
// One instance per nozzle (it holds the last level). Levels: ascending, up to 16.
class DutyQuantiser {
 public:
  static constexpr std::size_t kMaxLevels = 16;
  // Throws std::invalid_argument (empty, > 16, not ascending, outside [0, 100], hyst < 0).
  DutyQuantiser(std::span<const double> levels_pct, double hysteresis_pct);

  double quantise(double duty_pct) noexcept;
  void reset() noexcept { has_level_ = false; }
  double level_pct() const noexcept { return has_level_ ? levels_[current_] : 0.0; }

 private:
  std::array<double, kMaxLevels> levels_{};
  std::size_t count_ = 0;
  double hysteresis_pct_ = 0.0;
  std::size_t current_ = 0;
  bool has_level_ = false;
};

// The 2018 paper's six density levels are classified where the densities are measured:
// vision/zones.hpp (classify_density, DensityLevelCuts), reported per zone in FrameResult.

}  // namespace weedspray::control
