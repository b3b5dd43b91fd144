// SPDX-License-Identifier: Apache-2.0
#include "control/fuzzy_pid.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <tuple>

namespace weedspray::control {
namespace {

constexpr double kDomain = 6.0;
constexpr double kHalfWidth = 2.0;
using StrengthTable = std::array<std::array<double, kFuzzyTermCount>, kFuzzyTermCount>;

// Output side: plain triangles, the domain is [-6, 6] so NB/PB are their inner halves.
double output_membership(FuzzyTerm term, double z) noexcept {
  return std::max(0.0, 1.0 - std::abs(z - fuzzy_term_centre(term)) / kHalfWidth);
}

StrengthTable rule_strengths(double qe, double qec) noexcept {
  std::array<double, kFuzzyTermCount> mu_e{};
  std::array<double, kFuzzyTermCount> mu_ec{};
  for (int t = 0; t < kFuzzyTermCount; ++t) {
    mu_e[t] = fuzzy_input_membership(static_cast<FuzzyTerm>(t), qe);
    mu_ec[t] = fuzzy_input_membership(static_cast<FuzzyTerm>(t), qec);
  }
  StrengthTable strength{};
  for (int i = 0; i < kFuzzyTermCount; ++i) {
    for (int j = 0; j < kFuzzyTermCount; ++j) strength[i][j] = std::min(mu_e[i], mu_ec[j]);
  }
  return strength;
}

// Exact integrals of the merged output set mu(z) = max_t min(s_t, tri_t(z)) over [-6, 6]:
// returns {integral of mu, integral of mu z}. Between two adjacent term centres only those two
// triangles are non-zero, and there mu is the max/min of four linear pieces (two clip levels,
// a falling and a rising edge), so it is linear between their pairwise crossings.
std::pair<double, double> exact_moments(
    const std::array<double, kFuzzyTermCount>& term_strength) noexcept {
  double area = 0.0;
  double moment = 0.0;
  for (int t = 0; t + 1 < kFuzzyTermCount; ++t) {
    const double s0 = term_strength[t];
    const double s1 = term_strength[t + 1];
    if (s0 <= 0.0 && s1 <= 0.0) continue;
    const double c = fuzzy_term_centre(static_cast<FuzzyTerm>(t));
    // Local coordinate x in [0, 2]: falling edge 1 - x/2 (term t), rising edge x/2 (term t+1).
    auto mu = [&](double x) {
      return std::max(std::min(s0, 1.0 - 0.5 * x), std::min(s1, 0.5 * x));
    };
    std::array<double, 8> cuts{
        0.0, 2.0, 1.0, 2.0 * (1.0 - s0), 2.0 * s0, 2.0 * s1, 2.0 * (1.0 - s1), 0.0};
    std::size_t count = 7;
    for (std::size_t k = 0; k < count; ++k) cuts[k] = std::clamp(cuts[k], 0.0, 2.0);
    std::sort(cuts.begin(), cuts.begin() + static_cast<std::ptrdiff_t>(count));
    for (std::size_t k = 0; k + 1 < count; ++k) {
      const double a = cuts[k];
      const double b = cuts[k + 1];
      if (b <= a) continue;
      const double fa = mu(a);
      const double fb = mu(b);
      const double za = c + a;
      const double zb = c + b;
      area += 0.5 * (b - a) * (fa + fb);
      // Integral of a linear f times z over [za, zb].
      moment += (b - a) / 6.0 * (fa * (2.0 * za + zb) + fb * (za + 2.0 * zb));
    }
  }
  return {area, moment};
}

}  // namespace

double fuzzy_input_membership(FuzzyTerm term, double x) noexcept {
  if (!std::isfinite(x)) return 0.0;
  const double centre = fuzzy_term_centre(term);
  if (term == FuzzyTerm::NB && x <= centre) return 1.0;
  if (term == FuzzyTerm::PB && x >= centre) return 1.0;
  return std::max(0.0, 1.0 - std::abs(x - centre) / kHalfWidth);
}

double fuzzy_quantise(double value, double range) noexcept {
  if (!(range > 0.0) || !std::isfinite(value)) return 0.0;
  return std::clamp(kDomain * value / range, -kDomain, kDomain);
}

double fuzzy_defuzzify(const FuzzyRuleTable& rules, const StrengthTable& strength,
                       const FuzzyInferenceConfig& config) noexcept {
  // Strength reaching each output term: max over the rules naming it (Mamdani max-aggregation).
  std::array<double, kFuzzyTermCount> term_strength{};
  for (int i = 0; i < kFuzzyTermCount; ++i) {
    for (int j = 0; j < kFuzzyTermCount; ++j) {
      const auto t = static_cast<int>(rules[i][j]);
      term_strength[t] = std::max(term_strength[t], strength[i][j]);
    }
  }
  double weighted = 0.0;
  double total = 0.0;
  if (config.defuzzification == FuzzyDefuzzification::kExactCentroid) {
    std::tie(total, weighted) = exact_moments(term_strength);
  } else if (config.defuzzification == FuzzyDefuzzification::kTermCentres) {
    for (int t = 0; t < kFuzzyTermCount; ++t) {
      weighted += term_strength[t] * fuzzy_term_centre(static_cast<FuzzyTerm>(t));
      total += term_strength[t];
    }
  } else {
    const double step = config.output_step > 0.0 ? config.output_step : 0.01;
    const auto samples = static_cast<long>(std::lround(2.0 * kDomain / step));
    // Only the fired terms (at most four for two inputs) and only their support are sampled:
    // membership is zero elsewhere, so the sum is unchanged and the table builds faster.
    std::array<int, kFuzzyTermCount> active{};
    int active_count = 0;
    double lo = kDomain, hi = -kDomain;
    for (int t = 0; t < kFuzzyTermCount; ++t) {
      if (term_strength[t] <= 0.0) continue;
      active[active_count++] = t;
      const double centre = fuzzy_term_centre(static_cast<FuzzyTerm>(t));
      lo = std::min(lo, centre - kHalfWidth);
      hi = std::max(hi, centre + kHalfWidth);
    }
    if (active_count == 0) return 0.0;
    const double scale = static_cast<double>(samples) / (2.0 * kDomain);
    const long k_lo = std::max(0L, static_cast<long>(std::floor((lo + kDomain) * scale)));
    const long k_hi = std::min(samples, static_cast<long>(std::ceil((hi + kDomain) * scale)));
    for (long k = k_lo; k <= k_hi; ++k) {
      const double z = -kDomain + 2.0 * kDomain * static_cast<double>(k) / samples;
      double mu = 0.0;
      for (int a = 0; a < active_count; ++a) {
        const int t = active[a];
        mu = std::max(mu,
                      std::min(term_strength[t], output_membership(static_cast<FuzzyTerm>(t), z)));
      }
      // Trapezoid rule: the end samples count half, so the sum approximates the integral.
      const double w = (k == 0 || k == samples) ? 0.5 : 1.0;
      weighted += w * mu * z;
      total += w * mu;
    }
  }
  return total > 0.0 ? weighted / total : 0.0;
}

FuzzyGainCorrection fuzzy_infer(double qe, double qec,
                                const FuzzyInferenceConfig& config) noexcept {
  const StrengthTable strength =
      rule_strengths(std::clamp(qe, -kDomain, kDomain), std::clamp(qec, -kDomain, kDomain));
  return FuzzyGainCorrection{fuzzy_defuzzify(kDeltaKpRules, strength, config),
                             fuzzy_defuzzify(kDeltaKiRules, strength, config),
                             fuzzy_defuzzify(kDeltaKdRules, strength, config)};
}

FuzzyGainTable::FuzzyGainTable(const FuzzyInferenceConfig& config, int steps_per_unit)
    : inference_(config), steps_per_unit_(steps_per_unit) {
  if (steps_per_unit < 1 || steps_per_unit > 100) {
    throw std::invalid_argument("fuzzy table_steps_per_unit must be in 1..100, got " +
                                std::to_string(steps_per_unit));
  }
  if (!(config.output_step > 0.0) || config.output_step > 1.0) {
    throw std::invalid_argument("fuzzy output_step must be in (0, 1]");
  }
  side_ = static_cast<std::size_t>(2 * 6 * steps_per_unit + 1);
  grid_.resize(side_ * side_);
  for (std::size_t i = 0; i < side_; ++i) {
    const double qe = -kDomain + static_cast<double>(i) / steps_per_unit;
    for (std::size_t j = 0; j < side_; ++j) {
      const double qec = -kDomain + static_cast<double>(j) / steps_per_unit;
      grid_[i * side_ + j] = fuzzy_infer(qe, qec, config);
    }
  }
}

std::shared_ptr<const FuzzyGainTable> shared_fuzzy_gain_table(const FuzzyInferenceConfig& config,
                                                              int steps_per_unit) {
  using Key = std::tuple<int, double, int>;
  static std::mutex mutex;
  static std::map<Key, std::shared_ptr<const FuzzyGainTable>> tables;
  // Only the sampled centroid depends on output_step.
  const double step =
      config.defuzzification == FuzzyDefuzzification::kSampledCentroid ? config.output_step : 0.0;
  const Key key{static_cast<int>(config.defuzzification), step, steps_per_unit};
  const std::lock_guard lock(mutex);
  auto& table = tables[key];
  if (!table) table = std::make_shared<const FuzzyGainTable>(config, steps_per_unit);
  return table;
}

FuzzyGainCorrection FuzzyGainTable::lookup(double qe, double qec) const noexcept {
  if (!std::isfinite(qe)) qe = 0.0;
  if (!std::isfinite(qec)) qec = 0.0;
  const double last = static_cast<double>(side_ - 1);
  const double u = std::clamp((qe + kDomain) * steps_per_unit_, 0.0, last);
  const double v = std::clamp((qec + kDomain) * steps_per_unit_, 0.0, last);
  const auto i0 = std::min(static_cast<std::size_t>(u), side_ - 2);
  const auto j0 = std::min(static_cast<std::size_t>(v), side_ - 2);
  const double fu = u - static_cast<double>(i0);
  const double fv = v - static_cast<double>(j0);
  const FuzzyGainCorrection& a = grid_[i0 * side_ + j0];
  const FuzzyGainCorrection& b = grid_[i0 * side_ + j0 + 1];
  const FuzzyGainCorrection& c = grid_[(i0 + 1) * side_ + j0];
  const FuzzyGainCorrection& d = grid_[(i0 + 1) * side_ + j0 + 1];
  auto blend = [&](double FuzzyGainCorrection::*field) {
    const double top = a.*field + fv * (b.*field - a.*field);
    const double bottom = c.*field + fv * (d.*field - c.*field);
    return top + fu * (bottom - top);
  };
  return FuzzyGainCorrection{blend(&FuzzyGainCorrection::d_kp), blend(&FuzzyGainCorrection::d_ki),
                             blend(&FuzzyGainCorrection::d_kd)};
}

namespace {

const FuzzyPidConfig& checked(const FuzzyPidConfig& config) {
  if (!(config.error_range > 0.0) || !std::isfinite(config.error_range)) {
    throw std::invalid_argument("FuzzyPidConfig.error_range (Vmax - Vmin) must be > 0");
  }
  if (!(config.error_rate_range >= 0.0) || !std::isfinite(config.error_rate_range)) {
    throw std::invalid_argument("FuzzyPidConfig.error_rate_range must be >= 0 (0 = 2 * range)");
  }
  const PidGains& c = config.correction_weights;
  if (!std::isfinite(c.kp) || !std::isfinite(c.ki) || !std::isfinite(c.kd)) {
    throw std::invalid_argument("FuzzyPidConfig.correction_weights must be finite");
  }
  return config;
}

}  // namespace

FuzzyPid::FuzzyPid(const FuzzyPidConfig& config)
    : config_(checked(config)),
      table_(shared_fuzzy_gain_table(config.inference, config.table_steps_per_unit)),
      pid_(config.base) {}

double FuzzyPid::update(double setpoint, double measurement, double dt_s) noexcept {
  if (!std::isfinite(setpoint) || !std::isfinite(measurement) || !std::isfinite(dt_s) ||
      dt_s <= 0.0) {
    return pid_.output();
  }
  const double error = setpoint - measurement;
  // Error rate from the measurement (de/dt = -dy/dt for a constant set-point).
  const double error_rate = has_previous_ ? -(measurement - previous_measurement_) / dt_s : 0.0;
  previous_measurement_ = measurement;
  has_previous_ = true;

  const double rate_range =
      config_.error_rate_range > 0.0 ? config_.error_rate_range : 2.0 * config_.error_range;
  correction_ = table_->lookup(fuzzy_quantise(error, config_.error_range),
                               fuzzy_quantise(error_rate, rate_range));
  const PidGains& base = config_.base.gains;
  const PidGains& w = config_.correction_weights;
  pid_.set_gains(PidGains{std::max(0.0, base.kp + correction_.d_kp * w.kp),
                          std::max(0.0, base.ki + correction_.d_ki * w.ki),
                          std::max(0.0, base.kd + correction_.d_kd * w.kd)});
  return pid_.update(setpoint, measurement, dt_s);
}

void FuzzyPid::enable(double current_output, double setpoint, double measurement) noexcept {
  pid_.enable(current_output, setpoint, measurement);
  previous_measurement_ = measurement;
  has_previous_ = std::isfinite(measurement);
}

void FuzzyPid::reset() noexcept {
  pid_.reset();
  pid_.set_gains(config_.base.gains);
  has_previous_ = false;
  correction_ = FuzzyGainCorrection{};
}

}  // namespace weedspray::control
