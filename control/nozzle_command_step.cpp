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
      pwm_period_s_(config.pwm_period_s),
      cycle_s_(config.cycle_s),
      phase_offset_s_(config.phase_offset_s),
      trim_(config.trim) {
  if (!(std::isfinite(config.pwm_period_s) && config.pwm_period_s >= 0.0))
    throw std::invalid_argument("NozzleCommandConfig.pwm_period_s must be >= 0");
  if (!(std::isfinite(config.cycle_s) && config.cycle_s >= 0.0))
    throw std::invalid_argument("NozzleCommandConfig.cycle_s must be >= 0");
  chosen_period_.fill(-1);
}

double NozzleCommandStep::alternating_duty_pct(std::size_t n, const NozzleCommandInputs& in,
                                               double target, double pressure) noexcept {
  const NozzleLine& line = in.lines[n];
  const double top_pct = in.law.max_duty_pct;
  if (!(pwm_period_s_ > 0.0) || in.schedule_time_s < 0.0 ||
      !(line.full_open_flow_l_per_min > 0.0) || !(top_pct > 0.0 && top_pct < 100.0))
    return -1.0;
  const double top = flow_for_duty_l_per_min(line, top_pct, pressure);
  const double open = held_open_flow_l_per_min(line, pressure);
  if (!(target > top && target < open)) return -1.0;
  // The period the valve latches next: the one under the next cycle.
  const auto period = static_cast<std::int64_t>(
      std::floor((in.schedule_time_s + cycle_s_ - phase_offset_s_[n]) / pwm_period_s_));
  if (period != chosen_period_[n]) {
    chosen_period_[n] = period;
    open_credit_[n] += (target - top) / (open - top);
    chosen_open_[n] = open_credit_[n] >= 0.5;
    if (chosen_open_[n]) open_credit_[n] -= 1.0;
  }
  return chosen_open_[n] ? 100.0 : top_pct;
}

const NozzleCommandOutputs& NozzleCommandStep::step(const NozzleCommandInputs& in) noexcept {
  const double filtered = compensation_filter_.update(in.pressure_mpa, in.dt_s);
  const double pressure = in.pressure_compensation ? filtered : 0.0;
  out_.compensation_pressure_mpa = pressure;
  const std::size_t nozzles =
      std::min({nozzles_, in.target_flow_l_per_min.size(), in.lines.size()});
  out_.alternating_mask = 0;
  for (std::size_t n = 0; n < nozzles; ++n) {
    const double target = in.target_flow_l_per_min[n];
    double duty = 0.0;
    const double alternating =
        in.spraying && target > 0.0 ? alternating_duty_pct(n, in, target, pressure) : -1.0;
    if (alternating >= 0.0) {
      duty = alternating;
      out_.alternating_mask |= std::uint32_t{1} << n;
    } else if (in.spraying && target > 0.0) {
      const double raw = raw_duty_for_flow_pct(in.lines[n], target, pressure);
      duty = quantised_ ? quantisers_[n].quantise(std::clamp(raw, 0.0, 100.0)) : raw;
      duty = clamp_duty_for_flow_pct(in.law, duty, target);
    } else if (quantised_) {
      quantisers_[n].reset();
    }
    if (alternating < 0.0) {  // out of the band above: the next stretch starts afresh
      open_credit_[n] = 0.0;
      chosen_period_[n] = -1;
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
