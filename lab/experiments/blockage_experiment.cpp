// SPDX-License-Identifier: Apache-2.0
// A nozzle blocked while spraying, found from the line flow meter.
#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <random>
#include <span>
#include <vector>

#include "lab/experiments/experiments.hpp"
#include "lab/experiments/vocabulary.hpp"

namespace weedspray::lab::experiments {
namespace {

// The field's demand as a share of each nozzle's full-open flow: the rate law's share at the
// nominal speed times the ground speed (the volume per area is kept), at most held open.
void field_demand_at(sim::FieldDutyProcess& field, double t_s, std::span<double> shares) {
  field.shares_at(t_s, shares);
  const double speed = field.speed_factor_at(t_s);
  for (double& share : shares) share = std::min(1.0, share * speed);
}

// The healthy part's shares, as BlockageMachine reports them: closures and the lag-1
// correlation (the pooled fit of each share on the one before).
struct ShareRecord {
  std::vector<double> before, after;
  std::size_t closed = 0, count = 0;

  void add(std::span<const double> previous, std::span<const double> shares) {
    for (std::size_t i = 0; i < shares.size(); ++i) {
      closed += shares[i] == 0.0 ? 1 : 0;
      ++count;
      if (previous.empty()) continue;
      before.push_back(previous[i]);
      after.push_back(shares[i]);
    }
  }
  double closed_share() const {
    return count > 0 ? static_cast<double>(closed) / static_cast<double>(count) : 0.0;
  }
  double lag_correlation() const {
    const bool varies =
        std::adjacent_find(before.begin(), before.end(), std::not_equal_to<>()) != before.end();
    if (!varies) return 0.0;
    const LineFit fit = fit_line(before, after);
    return std::copysign(std::sqrt(fit.r_squared), fit.slope);
  }
};

BlockageMachine blockage_once(const Machine& machine, std::uint64_t fleet_seed, int index,
                              const BlockageOptions& options) {
  CalibrationOptions cal_options;
  cal_options.seed = machine.seed;
  cal_options.pressure_mpa = options.pressure_mpa;
  cal_options.frequency_hz = options.frequency_hz;
  cal_options.plant = machine.params;
  const CalibrationResult& cal = cached_calibration(cal_options);

  RigConfig config;
  config.seed = machine.seed;
  config.plant = machine.params;
  config.setpoint_mpa = options.pressure_mpa;
  config.pwm_frequency_hz = options.frequency_hz;
  config.record_period_s = 0.0;
  config.fixes = {true, true, true};
  config.meter_pulses_per_l = cal.meter.pulses_per_litre;
  config.nozzle_health = options.health;
  ClosedLoopRig rig(config);
  std::vector<NozzleLine> lines;
  for (const auto& n : cal.nozzles) lines.push_back(n.fitted);
  rig.set_nozzle_lines(lines);
  const std::vector<double> full = calibrated_full_flows(cal);
  rig.set_full_open_flows(full);

  std::seed_seq seq{static_cast<std::uint32_t>(fleet_seed), static_cast<std::uint32_t>(index), 3U};
  std::mt19937_64 rng(seq);
  std::uniform_real_distribution<double> share(0.3, 0.9);
  BlockageMachine out;
  out.blocked_nozzle = std::uniform_int_distribution<int>(0, rig.plant().nozzle_count() - 1)(rng);
  std::optional<sim::FieldDutyProcess> field;
  if (options.duties == BlockageDuties::kField) field.emplace(full.size(), rng(), options.field);
  std::vector<double> shares(full.size());
  auto redraw = [&] {
    if (field) {
      field_demand_at(*field, rig.time_s(), shares);
    } else {
      for (double& s : shares) s = share(rng);
    }
    std::vector<double> flows(full.size());
    for (std::size_t i = 0; i < full.size(); ++i) flows[i] = shares[i] * full[i];
    rig.request_flows(flows);
  };
  redraw();
  ShareRecord record;
  record.add({}, shares);
  rig.start();
  const NozzleHealth& health = *rig.nozzle_health();
  const double healthy_end = options.health.baseline_s + options.healthy_s;
  while (rig.time_s() < healthy_end - 1e-9) {
    rig.run_for(options.redraw_s);
    const std::vector<double> previous = shares;
    redraw();
    record.add(previous, shares);
    if (health.baseline_ready())
      for (int i = 0; i < rig.plant().nozzle_count(); ++i)
        out.healthy_worst_deviation = std::max(
            out.healthy_worst_deviation, std::abs(health.ratio(static_cast<std::size_t>(i)) - 1.0));
  }
  out.closed_share = record.closed_share();
  out.share_lag_correlation = record.lag_correlation();
  out.healthy_max_evidence = rig.health_max_evidence();
  out.false_alarm = health.alarmed_nozzle() >= 0;
  if (out.false_alarm) return out;
  rig.plant().set_nozzle_blockage(out.blocked_nozzle, options.blockage);
  const double blocked_at = rig.time_s();
  const double step = 0.05;
  double next_redraw = blocked_at + options.redraw_s;
  while (rig.time_s() < blocked_at + 3.0 * options.detect_limit_s) {
    rig.run_for(step);
    if (health.alarmed_nozzle() >= 0) {
      out.named_nozzle = health.alarmed_nozzle();
      out.detect_s = rig.time_s() - blocked_at;
      break;
    }
    if (rig.time_s() >= next_redraw - 1e-9) {
      redraw();
      next_redraw += options.redraw_s;
    }
  }
  return out;
}

}  // namespace

BlockageFleetResult run_blockage_fleet(const FleetOptions& fleet, const BlockageOptions& options) {
  BlockageFleetResult r;
  const std::vector<Machine> machines = draw_machines(fleet.seed, fleet.plants);
  std::vector<double> detect;
  std::vector<double> scatter;
  std::vector<double> evidence;
  for (std::size_t i = 0; i < machines.size(); ++i) {
    const BlockageMachine m = blockage_once(machines[i], fleet.seed, static_cast<int>(i), options);
    r.false_alarms += m.false_alarm ? 1 : 0;
    scatter.push_back(m.healthy_worst_deviation);
    evidence.push_back(m.healthy_max_evidence);
    const bool right = m.named_nozzle == m.blocked_nozzle && m.detect_s >= 0.0;
    if (right) detect.push_back(m.detect_s);
    if (right && m.detect_s <= options.detect_limit_s) ++r.named_within_limit;
    r.machines.push_back(m);
  }
  r.detect_s = spread_of(detect);
  r.healthy_worst_deviation = spread_of(scatter);
  r.healthy_max_evidence = spread_of(evidence);
  r.healthy_minutes = static_cast<double>(machines.size()) * options.healthy_s / 60.0;
  return r;
}

}  // namespace weedspray::lab::experiments
