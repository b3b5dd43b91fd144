// SPDX-License-Identifier: Apache-2.0
// A nozzle blocked while spraying (or from the job's start), found from the line flow meter:
// by a passive judge on the spraying or by the re-check on the headlands.
#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <random>
#include <span>
#include <stdexcept>
#include <vector>

#include "lab/experiments/experiments.hpp"
#include "lab/experiments/rig_recheck.hpp"
#include "lab/experiments/speed_target.hpp"
#include "lab/experiments/vocabulary.hpp"

namespace weedspray::lab::experiments {
namespace {

// The field's demand as a share of each nozzle's full-open flow: the share at the nominal speed
// through the daemon's rate law at the ground speed (speed_target.hpp: the volume per area is
// kept), at most held open.
void field_demand_at(sim::FieldDutyProcess& field, double t_s, std::span<double> shares) {
  field.shares_at(t_s, shares);
  const double speed = field.speed_factor_at(t_s);
  for (double& share : shares)
    share = speed_following_flow(share, 1.0, 1.0, speed, 1.0).flow_l_per_min;
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

// Seconds from `t_s` to the end of the first headland that starts after it (one headland
// cycle: the next headland whatever the phase, and its end); 0 without headlands.
double to_end_of_next_headland_s(const sim::FieldDutyOptions& field, double t_s) {
  const double every = field.headland_every_s;
  const double length = field.headland_s;
  if (!(every > 0) || !(length > 0)) return 0.0;
  const double first = every - length;  // the first headland's start
  const double start = first + std::ceil((t_s - first) / every) * every;
  return start + length - t_s;
}

RigRecheckSettings recheck_settings(const BlockageOptions& options) {
  return {options.recheck_config, options.pressure_mpa, options.pressure_tolerance_mpa,
          options.recheck_slice_s};
}

BlockageMachine blockage_once(const Machine& machine, std::uint64_t fleet_seed, int index,
                              const BlockageOptions& options) {
  CalibratedMachine calibrated =
      calibrate_as_made(machine.seed, machine.params, options.pressure_mpa, options.frequency_hz);
  calibrated.config.nozzle_health = options.health;
  ClosedLoopRig rig = calibrated_rig(calibrated);
  const std::vector<NozzleLine>& lines = calibrated.lines;
  const std::vector<double>& full = calibrated.full_flows;

  std::seed_seq seq{static_cast<std::uint32_t>(fleet_seed), static_cast<std::uint32_t>(index), 3U};
  std::mt19937_64 rng(seq);
  std::uniform_real_distribution<double> share(0.3, 0.9);
  BlockageMachine out;
  out.blocked_nozzle = std::uniform_int_distribution<int>(0, rig.plant().nozzle_count() - 1)(rng);
  std::optional<sim::FieldDutyProcess> field;
  if (options.duties == BlockageDuties::kField) field.emplace(full.size(), rng(), options.field);
  std::optional<RigRecheck> recheck;
  if (options.recheck && field)
    recheck.emplace(recheck_settings(options), lines, full, calibrated.config.meter_pulses_per_l);
  std::vector<double> shares(full.size());
  std::vector<double> flows(full.size());
  auto redraw = [&] {
    if (field) {
      field_demand_at(*field, rig.time_s(), shares);
    } else {
      for (double& s : shares) s = share(rng);
    }
    for (std::size_t i = 0; i < full.size(); ++i) flows[i] = shares[i] * full[i];
    // While the re-check holds a nozzle open nothing else is sprayed: it asks again on letting go.
    if (!recheck || !recheck->overriding()) rig.request_flows(flows);
  };
  auto respray = [&] { rig.request_flows(flows); };
  auto advance = [&](double seconds) {
    if (recheck) {
      // The window: the field's headland for the whole next slice.
      const auto headland = [&](double now, double next) {
        return field->headland_at(now) && field->headland_at(next);
      };
      recheck->run(rig, seconds, headland, respray);
    } else {
      rig.run_for(seconds);
    }
  };
  auto named = [&] {
    return recheck ? recheck->recheck().alarmed_nozzle() : rig.nozzle_health()->alarmed_nozzle();
  };
  if (options.blocked_at_start)
    rig.plant().set_nozzle_blockage(out.blocked_nozzle, options.blockage);
  redraw();
  ShareRecord record;
  record.add({}, shares);
  rig.start();
  const NozzleHealth& health = *rig.nozzle_health();
  const double healthy_end =
      options.blocked_at_start ? 0.0 : options.health.baseline_s + options.healthy_s;
  while (rig.time_s() < healthy_end - 1e-9) {
    advance(options.redraw_s);
    const std::vector<double> previous = shares;
    redraw();
    record.add(previous, shares);
    if (health.baseline_ready())
      for (int i = 0; i < rig.plant().nozzle_count(); ++i)
        out.healthy_worst_deviation = std::max(
            out.healthy_worst_deviation, std::abs(health.ratio(static_cast<std::size_t>(i)) - 1.0));
    out.false_alarm = out.false_alarm || named() >= 0;
    if (recheck)
      for (std::size_t i = 0; i < full.size(); ++i)
        out.healthy_reading_deviation =
            std::max(out.healthy_reading_deviation, std::abs(recheck->recheck().ratio(i) - 1.0));
  }
  out.closed_share = record.closed_share();
  out.share_lag_correlation = record.lag_correlation();
  out.healthy_max_evidence = rig.health_max_evidence();
  if (recheck) out.healthy_rechecks = static_cast<int>(recheck->recheck().completed());
  if (out.false_alarm) return out;
  if (!options.blocked_at_start)
    rig.plant().set_nozzle_blockage(out.blocked_nozzle, options.blockage);
  const double blocked_at = rig.time_s();
  out.limit_s = options.detect_limit_s;
  if (field)
    out.limit_s = std::max(out.limit_s, to_end_of_next_headland_s(options.field, blocked_at));
  const double blocked_read_before =
      recheck ? recheck->recheck().measured_at_s(static_cast<std::size_t>(out.blocked_nozzle))
              : 0.0;
  const double step = 0.05;
  double next_redraw = blocked_at + options.redraw_s;
  const double record_end =
      blocked_at + std::max(3.0 * options.detect_limit_s,
                            out.limit_s + (field ? options.field.headland_every_s : 0.0));
  while (rig.time_s() < record_end) {
    advance(step);
    if (named() >= 0) {
      out.named_nozzle = named();
      out.detect_s = rig.time_s() - blocked_at;
      break;
    }
    if (rig.time_s() >= next_redraw - 1e-9) {
      redraw();
      next_redraw += options.redraw_s;
    }
  }
  if (recheck) {
    const auto blocked = static_cast<std::size_t>(out.blocked_nozzle);
    if (recheck->recheck().measured_at_s(blocked) != blocked_read_before)
      out.blocked_ratio = recheck->recheck().ratio(blocked);
  }
  return out;
}

}  // namespace

BlockageFleetResult run_blockage_fleet(const FleetOptions& fleet, const BlockageOptions& options) {
  if (options.recheck && options.duties != BlockageDuties::kField)
    throw std::invalid_argument(
        "the headland re-check needs headlands: field duties (or a passive judge for iid)");
  BlockageFleetResult r;
  const std::vector<Machine> machines = draw_machines(fleet.seed, fleet.plants);
  std::vector<double> detect;
  std::vector<double> scatter;
  std::vector<double> evidence;
  std::vector<double> readings;
  for (std::size_t i = 0; i < machines.size(); ++i) {
    const BlockageMachine m = blockage_once(machines[i], fleet.seed, static_cast<int>(i), options);
    r.false_alarms += m.false_alarm ? 1 : 0;
    scatter.push_back(m.healthy_worst_deviation);
    evidence.push_back(m.healthy_max_evidence);
    if (options.recheck) readings.push_back(m.healthy_reading_deviation);
    const bool right = m.named_nozzle == m.blocked_nozzle && m.detect_s >= 0.0;
    if (right) detect.push_back(m.detect_s);
    if (right && m.detect_s <= m.limit_s) ++r.named_within_limit;
    r.machines.push_back(m);
  }
  r.detect_s = spread_of(detect);
  r.healthy_worst_deviation = spread_of(scatter);
  r.healthy_max_evidence = spread_of(evidence);
  r.healthy_reading_deviation = spread_of(readings);
  r.healthy_minutes = options.blocked_at_start
                          ? 0.0
                          : static_cast<double>(machines.size()) * options.healthy_s / 60.0;
  return r;
}

}  // namespace weedspray::lab::experiments
