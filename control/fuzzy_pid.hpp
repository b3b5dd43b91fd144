// SPDX-License-Identifier: Apache-2.0
// Fuzzy-adaptive PID (SPEC §4, UGV paper dong2024 §2.3): a PID whose gains are corrected
// every cycle from the error e and its rate of change ec.
//
// Quantisation onto {-6..6}, clamped:  f(e) = 6 e / R,  f(ec) = 6 ec / Rc, where R is the
// declared pressure range Vmax - Vmin and Rc the range of ec (the paper's 2 (Vmax - Vmin)).
// Here ec is the error RATE de/dt in units/s (computed from the measurement, so set-point
// steps do not spike it); Rc therefore has units/s and defaults to 2 R per second.
// Membership: seven triangles NB..PB centred at -6 -4 -2 0 2 4 6, half-width 2; NB and PB are
// shoulders (membership 1 beyond -6 / 6). Inference: Mamdani, rule strength = min(mu_e, mu_ec)
// over the 49 rules of fuzzy_rules.hpp.
// Defuzzification (dK = sum mu(z) z / sum mu(z) over the output domain), three documented ways:
//  - kExactCentroid (default): the same clipped-and-merged output set as kSampledCentroid, its
//    centroid integrated exactly (the set is piecewise linear, so each piece integrates in
//    closed form). The limit of kSampledCentroid as output_step -> 0, and ~100x cheaper.
//  - kSampledCentroid: the output terms are clipped at their rule strength, merged
//    by max, and the centroid is taken over the output domain [-6, 6] sampled every
//    output_step (0.01 by default; the output triangles NB/PB are the halves inside [-6, 6]).
//    Full-membership PB alone therefore gives 16/3 = 5.33, not 6.
//  - kTermCentres: the weighted mean of the output term centres, weights = the max rule
//    strength reaching each term (a singleton COG). Full-membership PB alone gives 6.
// Gains: Kp = Kp' + dKp Cp, Ki = Ki' + dKi Ci, Kd = Kd' + dKd Cd, floored at 0.
// The inference is precomputed at configure time into a query table on a grid of quantised
// (e, ec) with table_steps_per_unit points per unit; update() interpolates bilinearly, so the
// per-cycle cost is a few multiplies and no allocation. The table depends only on the rules
// and the inference settings, never on the base gains or the correction weights, so one table
// per (inference, resolution) is built per process and shared by every FuzzyPid
// (shared_fuzzy_gain_table); gains and weights can change between cycles without a rebuild.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "control/fuzzy_rules.hpp"
#include "control/pid.hpp"

namespace weedspray::control {

enum class FuzzyDefuzzification { kExactCentroid, kSampledCentroid, kTermCentres };

// dKp, dKi, dKd on the quantised domain [-6, 6].
struct FuzzyGainCorrection {
  double d_kp = 0.0;
  double d_ki = 0.0;
  double d_kd = 0.0;
};

// Membership of the quantised value x in term (input side: NB/PB are shoulders).
double fuzzy_input_membership(FuzzyTerm term, double x) noexcept;

// Quantisation onto the domain, clamped to [-6, 6]; range <= 0 gives 0.
double fuzzy_quantise(double value, double range) noexcept;

struct FuzzyInferenceConfig {
  FuzzyDefuzzification defuzzification = FuzzyDefuzzification::kExactCentroid;
  double output_step = 0.01;  // sampling step of the output domain (kSampledCentroid)
};

// Exact evaluation (no table) at quantised inputs qe, qec in [-6, 6]. Allocation-free.
FuzzyGainCorrection fuzzy_infer(double qe, double qec, const FuzzyInferenceConfig& config) noexcept;

// Centroid of one rule table's output for given rule strengths (exposed for tests):
// strength[e_term][ec_term] in [0, 1].
double fuzzy_defuzzify(
    const FuzzyRuleTable& rules,
    const std::array<std::array<double, kFuzzyTermCount>, kFuzzyTermCount>& strength,
    const FuzzyInferenceConfig& config) noexcept;

// Precomputed query table over the quantised (e, ec) square [-6, 6]^2.
class FuzzyGainTable {
 public:
  // steps_per_unit >= 1 (grid spacing 1/steps_per_unit); throws std::invalid_argument.
  FuzzyGainTable(const FuzzyInferenceConfig& config, int steps_per_unit);
  // Bilinear interpolation; inputs clamped to [-6, 6]. Allocation-free.
  FuzzyGainCorrection lookup(double qe, double qec) const noexcept;
  int steps_per_unit() const noexcept { return steps_per_unit_; }
  const FuzzyInferenceConfig& inference() const noexcept { return inference_; }

 private:
  FuzzyInferenceConfig inference_;
  int steps_per_unit_;
  std::size_t side_;                       // grid points per axis
  std::vector<FuzzyGainCorrection> grid_;  // row-major [e][ec]
};

// The process-wide table for these settings, built on first use (thread-safe; start-up only,
// it may allocate) and shared afterwards. Throws like the FuzzyGainTable constructor.
std::shared_ptr<const FuzzyGainTable> shared_fuzzy_gain_table(const FuzzyInferenceConfig& config,
                                                              int steps_per_unit);

struct FuzzyPidConfig {
  PidConfig base{};               // base gains Kp', Ki', Kd', output range, anti-windup
  PidGains correction_weights{};  // Cp, Ci, Cd (gain units per quantised unit)
  double error_range = 0.4;       // R = Vmax - Vmin, same units as the error (e.g. MPa)
  double error_rate_range = 0.0;  // Rc [units/s]; 0 = 2 * error_range per second
  FuzzyInferenceConfig inference{};
  int table_steps_per_unit = 10;  // query-table resolution (0.1 quantised units)
};

class FuzzyPid {
 public:
  // Throws std::invalid_argument naming the field (error_range <= 0, ...).
  explicit FuzzyPid(const FuzzyPidConfig& config);

  // One cycle: compute e, ec, correct the gains, run the PID. Allocation-free.
  double update(double setpoint, double measurement, double dt_s) noexcept;

  void enable(double current_output, double setpoint, double measurement) noexcept;
  void disable() noexcept { pid_.disable(); }
  bool enabled() const noexcept { return pid_.enabled(); }
  void reset() noexcept;

  const FuzzyPidConfig& config() const noexcept { return config_; }

  double output() const noexcept { return pid_.output(); }
  const PidGains& current_gains() const noexcept { return pid_.gains(); }
  const FuzzyGainCorrection& last_correction() const noexcept { return correction_; }
  const PidTerms& last_terms() const noexcept { return pid_.last_terms(); }

 private:
  FuzzyPidConfig config_;
  std::shared_ptr<const FuzzyGainTable> table_;
  Pid pid_;
  bool has_previous_ = false;
  double previous_measurement_ = 0.0;
  FuzzyGainCorrection correction_{};
};

}  // namespace weedspray::control
