#include "control/fuzzy_pid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

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
  if (config.defuzzification == FuzzyDefuzzification::kTermCentres) {
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
    : steps_per_unit_(steps_per_unit) {
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
      table_(config.inference, config.table_steps_per_unit),
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
  correction_ = table_.lookup(fuzzy_quantise(error, config_.error_range),
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
