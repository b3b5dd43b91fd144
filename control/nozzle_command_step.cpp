// SPDX-License-Identifier: Apache-2.0
#include "control/nozzle_command_step.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace weedspray::control {
namespace {

constexpr std::array<double, 2> kUnquantisedLevels{0.0, 100.0};

// DutyQuantiser has no empty state: every slot gets the configured levels (or a placeholder
// pair when the step does not quantise).
template <std::size_t... I>
std::array<DutyQuantiser, sizeof...(I)> make_quantisers(std::span<const double> levels,
                                                        double hysteresis_pct,
                                                        std::index_sequence<I...>) {
  return {((void)I, DutyQuantiser(levels, hysteresis_pct))...};
}

std::span<const double> quantiser_levels(const NozzleCommandConfig& config) {
  if (config.quantiser_level_count == 0) return kUnquantisedLevels;
  if (config.quantiser_level_count > config.quantiser_levels_pct.size())
    throw std::invalid_argument("NozzleCommandConfig.quantiser_level_count must be at most 16");
  return std::span<const double>(config.quantiser_levels_pct.data(), config.quantiser_level_count);
}

std::size_t checked_nozzles(const NozzleCommandConfig& config) {
  if (config.nozzles < 1 || config.nozzles > kMaxCommandNozzles)
    throw std::invalid_argument("NozzleCommandConfig.nozzles must be in [1, 32]");
  if (!(std::isfinite(config.compensation_filter_s) && config.compensation_filter_s > 0.0))
    throw std::invalid_argument("NozzleCommandConfig.compensation_filter_s must be > 0");
  return config.nozzles;
}

}  // namespace

NozzleCommandStep::NozzleCommandStep(const NozzleCommandConfig& config)
    : nozzles_(checked_nozzles(config)),
      quantised_(config.quantiser_level_count > 0),
      quantisers_(make_quantisers(quantiser_levels(config), config.quantiser_hysteresis_pct,
                                  std::make_index_sequence<kMaxCommandNozzles>{})),
      compensation_filter_(config.compensation_filter_s),
      trim_(config.trim) {}

const NozzleCommandOutputs& NozzleCommandStep::step(const NozzleCommandInputs& in) noexcept {
  const double filtered = compensation_filter_.update(in.pressure_mpa, in.dt_s);
  const double pressure = in.pressure_compensation ? filtered : 0.0;
  out_.compensation_pressure_mpa = pressure;
  const std::size_t nozzles =
      std::min({nozzles_, in.target_flow_l_per_min.size(), in.lines.size()});
  for (std::size_t n = 0; n < nozzles; ++n) {
    const double target = in.target_flow_l_per_min[n];
    double duty = 0.0;
    if (in.spraying && target > 0.0) {
      const double raw = raw_duty_for_flow_pct(in.lines[n], target, pressure);
      duty = quantised_ ? quantisers_[n].quantise(std::clamp(raw, 0.0, 100.0)) : raw;
      duty = clamp_duty_for_flow_pct(in.law, duty, target);
    } else if (quantised_) {
      quantisers_[n].reset();
    }
    out_.law_duty_pct[n] = duty;
    out_.duty_pct[n] = duty;
  }
  for (std::size_t n = nozzles; n < kMaxCommandNozzles; ++n) {
    out_.law_duty_pct[n] = 0.0;
    out_.duty_pct[n] = 0.0;
  }
  FlowTrimStepInputs trim;
  trim.dt_s = in.dt_s;
  trim.spraying = in.trim && in.spraying;
  trim.pressure_mpa = in.pressure_mpa;
  trim.setpoint_mpa = in.setpoint_mpa;
  trim.compensation_pressure_mpa = pressure;
  trim.pulses = in.pulses;
  trim.pulses_per_litre = in.pulses_per_litre;
  trim.duty_pct = std::span<double>(out_.duty_pct.data(), nozzles);
  trim.lines = in.lines.first(nozzles);
  trim.min_duty_pct = in.law.min_duty_pct;
  trim.max_duty_pct = in.law.max_duty_pct;
  out_.trim = trim_.step(trim);
  double open_sum = 0.0;
  for (std::size_t n = 0; n < nozzles; ++n) open_sum += out_.duty_pct[n] / 100.0;
  out_.open_fraction = open_sum / static_cast<double>(nozzles_);
  return out_;
}

}  // namespace weedspray::control
