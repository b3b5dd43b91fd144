// SPDX-License-Identifier: Apache-2.0
// The wheat paper's field-side checks: delivered vs theoretical flow over weed densities
// (dose), and liquid saved by variable vs uniform spraying over a field (savings).
// Both use the spray-rate law of control/spray_rate_law.hpp on a machine calibrated at the
// wheat paper's operating point (0.4 MPa, 5 Hz).
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "control/nozzle_scheduler.hpp"
#include "lab/experiments/experiments.hpp"
#include "lab/experiments/speed_target.hpp"
#include "lab/experiments/vocabulary.hpp"

namespace weedspray::lab::experiments {
namespace {

// Calibrated as made, the duties in the law's band.
CalibratedMachine calibrate(std::uint64_t seed, double pressure_mpa, double frequency_hz,
                            const SprayLawConfig& law, const plant::PlantParams& plant = {}) {
  CalibratedMachine m = calibrate_as_made(seed, plant, pressure_mpa, frequency_hz);
  m.config.duty_clamp = law;
  return m;
}

}  // namespace

DoseResult run_dose(const DoseOptions& options) {
  SprayLawConfig law;
  law.max_density = options.max_density;
  CalibratedMachine m =
      calibrate(options.seed, options.pressure_mpa, options.frequency_hz, law, options.plant);
  m.config.fixes.flow_feedback = options.flow_feedback;
  m.config.ground_speed_m_per_s = options.speed_m_per_s;
  DoseResult result;
  std::vector<double> x, y;
  const std::size_t nozzles = m.full_flows.size();
  for (double density : options.densities) {
    ClosedLoopRig rig = calibrated_rig(m);
    // Every nozzle at the law's flow for the density at the ground speed now (the change's
    // ramp, else speed_m_per_s), at most its full-open flow; nozzle 1's asked volume kept.
    std::vector<double> flows(nozzles);
    AskedFlow first;
    const auto ask = [&] {
      const double speed =
          options.follow_speed ? rig.plant().ground_speed_m_per_s() : options.speed_m_per_s;
      for (std::size_t i = 0; i < nozzles; ++i) {
        const AskedFlow asked = asked_flow(law, density, speed, m.full_flows[i]);
        flows[i] = asked.flow_l_per_min;
        if (i == 0) first = asked;
      }
      rig.request_flows(flows);
    };
    if (options.change) apply_change(rig.plant(), *options.change);
    ask();
    rig.start();
    rig.run_for(options.settle_s);
    const double v0 = rig.plant().nozzle_delivered_l(0);
    // The change's ramps (supply voltage, ground speed) move over the measured minute, the
    // targets with the speed.
    AskedVolume asked;
    const double step = m.config.control_period_s;
    for (double t = 0.0; t < options.run_s - 1e-9; t += step) {
      if (options.change) apply_change_progress(rig.plant(), *options.change, t / options.run_s);
      ask();
      asked.add(first, step);
      rig.run_for(step);
    }
    const double minutes = options.run_s / 60.0;
    const double q = asked.asked_l / minutes;
    DosePoint p;
    p.density = density;
    p.theoretical_l_per_min = q;
    p.clipped_l_per_min = asked.clipped_l / minutes;
    p.delivered_l_per_min = (rig.plant().nozzle_delivered_l(0) - v0) / minutes;
    p.duty_pct = rig.commanded_duties_pct()[0];
    result.points.push_back(p);
    x.push_back(p.theoretical_l_per_min);
    y.push_back(p.delivered_l_per_min);
    result.mean_error_pct += std::abs(p.delivered_l_per_min - q) / q * 100.0;
  }
  result.mean_error_pct /= static_cast<double>(result.points.size());
  result.r2 = fit_line(x, y).r_squared;
  return result;
}

DoseFleetResult run_dose_fleet(const FleetOptions& fleet, const DoseOptions& base) {
  std::vector<double> r2[2], mean[2], max[2], clipped[2];
  DoseFleetResult result;
  double speed_min = std::numeric_limits<double>::infinity(), speed_max = -speed_min;
  const std::vector<Machine> machines = draw_machines(fleet.seed, fleet.plants);
  for (std::size_t i = 0; i < machines.size(); ++i) {
    DoseOptions options = base;
    options.seed = machines[i].seed;
    options.plant = machines[i].params;
    options.change = fleet.changed ? draw_change(machines[i], fleet.seed, static_cast<int>(i))
                                   : no_change(machines[i]);
    for (const double speed :
         {options.change->speed_start_m_per_s, options.change->speed_end_m_per_s}) {
      speed_min = std::min(speed_min, speed);
      speed_max = std::max(speed_max, speed);
    }
    for (int trim = 0; trim < 2; ++trim) {
      options.flow_feedback = trim == 0;
      const DoseResult r = run_dose(options);
      double worst = 0.0, asked = 0.0, over = 0.0;
      for (const auto& p : r.points) {
        worst = std::max(worst, std::abs(p.delivered_l_per_min - p.theoretical_l_per_min) /
                                    p.theoretical_l_per_min * 100.0);
        asked += p.theoretical_l_per_min;
        over += p.clipped_l_per_min;
      }
      r2[trim].push_back(r.r2);
      mean[trim].push_back(r.mean_error_pct);
      max[trim].push_back(worst);
      clipped[trim].push_back(asked + over > 0.0 ? over / (asked + over) * 100.0 : 0.0);
    }
  }
  const auto row = [&](int trim) {
    return DoseFleetRow{spread_of(r2[trim], true), spread_of(mean[trim]), spread_of(max[trim]),
                        spread_of(clipped[trim])};
  };
  result.trim_on = row(0);
  result.trim_off = row(1);
  result.speed_min_m_per_s = machines.empty() ? base.speed_m_per_s : speed_min;
  result.speed_max_m_per_s = machines.empty() ? base.speed_m_per_s : speed_max;
  return result;
}

namespace {

// UGV paper geometry: camera 1 m above the ground imaging 1-3 m ahead of its nadir, nozzles
// 1.2 m behind the nadir, two zone rows per frame.
NozzleSchedulerConfig savings_scheduler_config(const SavingsOptions& options,
                                               const plant::PlantParams& plant) {
  NozzleSchedulerConfig c;
  const double near = 1.0, far = 1.0 + 2.0 * options.zone_length_m;
  const double height = 1.0;
  const double lo = std::atan(near / height), hi = std::atan(far / height);
  c.geometry.mount_height_m = height;
  c.geometry.tilt_from_vertical_rad = 0.5 * (lo + hi);
  c.geometry.vertical_fov_rad = hi - lo;
  c.geometry.camera_to_nozzle_m = 1.2;
  c.nozzles = 4;
  c.rows = 2;
  // Lead by the nominal dead time plus half the travel (the valve is half open then).
  c.opening_delay_s = plant.nozzle.open_delay_s + 0.5 * plant.nozzle.open_travel_s;
  c.closing_delay_s = plant.nozzle.close_delay_s + 0.5 * plant.nozzle.close_travel_s;
  c.plan_capacity = 16;
  return c;
}

constexpr double kStartUpS = 3.0;  // pressure start-up before the track begins

// Where the track's first zone starts on the ground [m of odometer]: far enough ahead that the
// first frame is taken after the start-up.
double track_start_m(const SavingsOptions& o) {
  return o.speed_m_per_s * kStartUpS + 1.0;
}

}  // namespace

SavingsRun run_savings_variable(const std::vector<std::array<double, 4>>& zone_densities,
                                const SavingsOptions& options, LowDutyPolicy policy,
                                double uniform_l) {
  SprayLawConfig law;
  law.max_density = options.max_density;
  law.decision_threshold = options.decision_threshold;
  law.low_duty_policy = policy;
  const CalibratedMachine m =
      calibrate(options.seed, options.pressure_mpa, options.frequency_hz, law, options.plant);
  const std::size_t nozzles = std::min<std::size_t>(4, m.full_flows.size());
  const std::size_t zones = zone_densities.size();
  const double length = options.zone_length_m;
  const double v = options.speed_m_per_s;
  SavingsRun run;
  run.policy = policy;

  // What the law decides for each nozzle-zone, as volume while the zone passes the nozzle.
  std::vector<std::array<double, 4>> target_l(zones);
  for (std::size_t z = 0; z < zones; ++z) {
    double zone_total = 0.0;
    for (std::size_t i = 0; i < nozzles; ++i) {
      NozzleLine line = m.lines[i];
      line.full_open_flow_l_per_min = m.full_flows[i];
      const double density = zone_densities[z][i];
      const SprayDecision d = spray_decision(law, line, density, v, options.pressure_mpa);
      const double flow = d.duty_pct <= 0.0 ? 0.0
                          : d.duty_pct >= 100.0
                              ? m.full_flows[i]
                              : flow_for_duty_l_per_min(line, d.duty_pct, options.pressure_mpa);
      if (d.target_flow_l_per_min > 0.0 && flow <= 0.0) ++run.unsprayed_weedy_zones;
      target_l[z][i] = flow * length / v / 60.0;
      zone_total += target_l[z][i];
    }
    run.zone_target_l.push_back(zone_total);
  }
  run.nozzle_zone_target_l = target_l;

  // Drive: frames pinned by the scheduler as the odometer reaches them; every control period
  // the law runs on the density the scheduler gives for the ground under each nozzle.
  NozzleScheduler scheduler(savings_scheduler_config(options, m.config.plant));
  const double c2n = scheduler.config().geometry.camera_to_nozzle_m;
  const double start = track_start_m(options);
  const GroundInterval footprint = ground_footprint(scheduler.config().geometry);
  const std::size_t frames = (zones + 1) / 2;
  // Frame f images zones 2f (near row) and 2f+1 (far row).
  auto frame_odometer = [&](std::size_t f) {
    return start + 2.0 * length * static_cast<double>(f) - footprint.near_m;
  };
  ClosedLoopRig rig = calibrated_rig(m);
  rig.request_flows(std::vector<double>(nozzles, 0.0));
  rig.start();
  std::size_t next_frame = 0;
  std::size_t next_boundary = 0;  // zone boundary the nozzles pass next (0 = track start)
  std::array<double, 4> at_boundary{};
  std::vector<double> flows(nozzles);
  const double dt = m.config.control_period_s;
  const double end_m = start + length * static_cast<double>(zones);
  while (true) {
    const double odometer = rig.plant().distance_m();
    while (next_frame < frames && odometer >= frame_odometer(next_frame) - 1e-9) {
      const std::size_t near_zone = 2 * next_frame;
      std::array<double, 8> rows{};  // row 0 = far (image top), row 1 = near
      for (std::size_t i = 0; i < nozzles; ++i) {
        rows[nozzles + i] = zone_densities[near_zone][i];
        rows[i] = near_zone + 1 < zones ? zone_densities[near_zone + 1][i] : 0.0;
      }
      scheduler.add_frame(odometer, std::span<const double>(rows.data(), 2 * nozzles));
      ++next_frame;
    }
    // Zone volumes: cumulative nozzle volume read as the ground under the nozzles crosses
    // each zone boundary.
    const double under_nozzles = odometer - c2n;
    while (next_boundary <= zones &&
           under_nozzles >= start + length * static_cast<double>(next_boundary) - 1e-9) {
      std::array<double, 4> now{};
      for (std::size_t i = 0; i < nozzles; ++i) now[i] = rig.plant().nozzle_delivered_l(int(i));
      if (next_boundary > 0) {
        const std::size_t z = next_boundary - 1;
        double zone_total = 0.0;
        for (std::size_t i = 0; i < nozzles; ++i) {
          const double d = now[i] - at_boundary[i];
          zone_total += d;
          run.nozzle_delivered_l[i] += d;
          if (target_l[z][i] > 0.0 && d < options.under_dose_fraction * target_l[z][i])
            ++run.under_dosed_zones;
        }
        run.zone_delivered_l.push_back(zone_total);
        run.variable_l += zone_total;
      }
      at_boundary = now;
      ++next_boundary;
    }
    if (under_nozzles >= end_m) break;
    for (std::size_t i = 0; i < nozzles; ++i)
      flows[i] = target_flow_l_per_min(law, scheduler.duty_at(i, odometer, v), v);
    rig.request_flows(flows);
    rig.run_for(dt);
  }
  run.savings_pct = uniform_l > 0 ? (1.0 - run.variable_l / uniform_l) * 100.0 : 0.0;
  return run;
}

SavingsResult run_savings(const std::vector<std::array<double, 4>>& zone_densities,
                          const SavingsOptions& options) {
  SprayLawConfig law;
  law.max_density = options.max_density;
  const CalibratedMachine m =
      calibrate(options.seed, options.pressure_mpa, options.frequency_hz, law, options.plant);
  const std::size_t nozzles = std::min<std::size_t>(4, m.full_flows.size());
  const double zone_s = options.zone_length_m / options.speed_m_per_s;
  SavingsResult result;
  result.zones = static_cast<int>(zone_densities.size() * nozzles);

  // Uniform spraying: every nozzle at the nominal flow q_nom over the whole track, which is
  // the flow the law gives the densest zone (D = k).
  const double uniform_q = target_flow_l_per_min(law, law.max_density, options.speed_m_per_s);
  std::array<double, 4> uniform_per_nozzle{};
  {
    ClosedLoopRig rig = calibrated_rig(m);
    rig.request_flows(std::vector<double>(nozzles, uniform_q));
    rig.start();
    rig.run_for(kStartUpS);
    std::array<double, 4> v0{};
    for (std::size_t i = 0; i < nozzles; ++i) v0[i] = rig.plant().nozzle_delivered_l(int(i));
    rig.run_for(zone_s * static_cast<double>(zone_densities.size()));
    for (std::size_t i = 0; i < nozzles; ++i) {
      uniform_per_nozzle[i] = rig.plant().nozzle_delivered_l(int(i)) - v0[i];
      result.uniform_l += uniform_per_nozzle[i];
    }
  }
  for (auto* run : {&result.equal_coverage, &result.spec_clamp}) {
    const LowDutyPolicy policy =
        run == &result.equal_coverage ? LowDutyPolicy::kRaiseToMin : LowDutyPolicy::kClose;
    *run = run_savings_variable(zone_densities, options, policy, result.uniform_l);
    for (std::size_t i = 0; i < nozzles; ++i)
      run->nozzle_savings_pct[i] =
          uniform_per_nozzle[i] > 0
              ? (1.0 - run->nozzle_delivered_l[i] / uniform_per_nozzle[i]) * 100.0
              : 0.0;
  }
  const SavingsRun& headline = result.equal_coverage;
  result.variable_l = headline.variable_l;
  result.savings_pct = headline.savings_pct;
  result.under_dosed_zones = headline.under_dosed_zones;
  result.unsprayed_weedy_zones = headline.unsprayed_weedy_zones;
  result.zone_target_l = headline.zone_target_l;
  result.zone_delivered_l = headline.zone_delivered_l;
  result.nozzle_savings_pct = headline.nozzle_savings_pct;
  return result;
}

TruthTally tally_against_truth(const SavingsRun& run,
                               const std::vector<std::array<ZoneTruth, 4>>& truth,
                               double weedy_share) {
  if (truth.size() != run.nozzle_zone_target_l.size()) {
    throw std::invalid_argument("savings truth: " + std::to_string(truth.size()) +
                                " zones of truth for a run of " +
                                std::to_string(run.nozzle_zone_target_l.size()) + " zones");
  }
  TruthTally tally;
  for (std::size_t z = 0; z < truth.size(); ++z) {
    for (std::size_t n = 0; n < 4; ++n) {
      const ZoneTruth& zone = truth[z][n];
      const bool sprayed = run.nozzle_zone_target_l[z][n] > 0.0;
      if (zone.weed >= weedy_share) {
        ++tally.weedy_zones;
        tally.weedy_left_dry += !sprayed;
      } else if (zone.crop >= weedy_share) {
        ++tally.crop_only_zones;
        tally.crop_only_sprayed += sprayed;
      }
    }
  }
  return tally;
}

SavingsFleetResult run_savings_fleet(const std::vector<std::array<double, 4>>& zone_densities,
                                     const FleetOptions& fleet, const SavingsOptions& base) {
  std::vector<double> savings, under, uniform, variable;
  for (const Machine& machine : draw_machines(fleet.seed, fleet.plants)) {
    SavingsOptions options = base;
    options.seed = machine.seed;
    options.plant = machine.params;
    const SavingsResult r = run_savings(zone_densities, options);
    savings.push_back(r.savings_pct);
    under.push_back(r.zones > 0 ? 100.0 * r.under_dosed_zones / r.zones : 0.0);
    uniform.push_back(r.uniform_l);
    variable.push_back(r.variable_l);
  }
  return {spread_of(savings, true), spread_of(under), spread_of(uniform), spread_of(variable)};
}

}  // namespace weedspray::lab::experiments
