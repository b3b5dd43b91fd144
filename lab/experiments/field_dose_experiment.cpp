// SPDX-License-Identifier: Apache-2.0
// The boom-total dose error over a field run (L/ha, what rate controllers are judged on): a
// calibrated, then changed machine sprays a field whose density and ground speed change, with
// the daemon's rate law, duty band and online trim.
//
// The field's shares (FieldDutyOptions min_share 0.4, max_share 0.65) are the demand at the law's
// nominal speed. A request asks for share x speed factor of the nozzle's calibrated full-open
// flow, the speed factor 0.8-1.2, through the daemon's rate law (speed_target.hpp), clipped at
// the full-open flow; the clipped volume is reported (none with these shares). On the drawn
// machines' calibrated lines (0.4 MPa, 5 Hz; the run's band_lo / band_hi) the flow at the band's
// 20 % duty is 0.23-0.30 of the held-open flow (not half of it) and at 80 % 0.81-0.85: the valves
// modulate about 0.30-0.81 of full flow. 0.4 x 0.8 = 0.32 and 0.65 x 1.2 = 0.78 keep every request
// inside that band, so the error measured is the controller's, not the band's policy. The field's
// default 0.3-0.9 measures the policy too: on seed 1's 20 machines it raised 0.8 % of the
// nozzle-time to duty_min and held 2.1 % open, which added +0.4 % to the mean error (0.77 against
// 0.37 % from the band's decision; worst 1.69 %). The raised and held-open nozzle-time are reported
// beside the error.
//
// What is left with the trim on is the meter's drift since the catch test: the trim makes the
// meter read what the lines promise, so a meter reading d high leaves the boom d low (over 20
// machines of seeds 1 and 7 the error is -0.98 x drift + 0.28 %, r = -0.99; the +0.28 %, sd
// 0.06 %, is common to the machines and not traced further). Only a new catch test removes it.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "daemon/sprayer/step_settings.hpp"
#include "lab/experiments/experiments.hpp"
#include "lab/experiments/speed_target.hpp"

namespace weedspray::lab::experiments {
namespace {

// Running sums of one field run: what was asked, what the band decided, where and how long.
struct FieldDoseTally {
  double target_l = 0.0;
  double law_l = 0.0;
  double area_m2 = 0.0;
  double spraying_s = 0.0;  // nozzle-seconds asked to spray
  double raised_s = 0.0;
  double held_open_s = 0.0;

  // One nozzle's request held for dt_s at ground speed speed_m_per_s.
  void add(const SprayLawConfig& law, const NozzleLine& line, double flow_l_per_min,
           double pressure_mpa, double speed_m_per_s, double dt_s) {
    if (!(flow_l_per_min > 0.0)) return;
    const double raw = raw_duty_for_flow_pct(line, flow_l_per_min, pressure_mpa);
    const double duty = clamp_duty_for_flow_pct(law, raw, flow_l_per_min);
    double decided = flow_l_per_min;
    if (duty >= 100.0 && raw < 100.0) {
      decided = held_open_flow_l_per_min(line, pressure_mpa);
      held_open_s += dt_s;
    } else if (duty > raw) {
      decided = flow_for_duty_l_per_min(line, duty, pressure_mpa);
      raised_s += dt_s;
    }
    target_l += flow_l_per_min * dt_s / 60.0;
    law_l += decided * dt_s / 60.0;
    area_m2 += speed_m_per_s * law.nozzle_width_m * dt_s;
    spraying_s += dt_s;
  }
};

double percent_off(double value, double reference) {
  return reference > 0.0 ? (value - reference) / reference * 100.0 : 0.0;
}

// The field machine `index` of fleet `seed` sprays (the same with the trim on and off).
std::uint64_t field_dose_seed(std::uint64_t seed, int index) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(index), 5U};
  return std::mt19937_64(seq)();
}

// Mean and sd of signed values; worst: the one largest in size, with its sign.
Spread signed_spread_of(const std::vector<double>& values) {
  Spread s = spread_of(values);
  s.worst = 0.0;
  for (double v : values)
    if (std::abs(v) > std::abs(s.worst)) s.worst = v;
  return s;
}

}  // namespace

sim::FieldDutyOptions field_dose_default_field() {
  sim::FieldDutyOptions field;
  field.min_share = 0.4;
  field.max_share = 0.65;
  return field;
}

SprayLawConfig field_dose_daemon_law() {
  return daemon::spray_law_config(daemon::default_settings());
}

FieldDoseRun run_field_dose(const Machine& machine, const MachineChange& change,
                            std::uint64_t field_seed, bool trim, const FieldDoseOptions& options) {
  CalibratedMachine calibrated =
      calibrate_as_made(machine.seed, machine.params, options.pressure_mpa, options.frequency_hz);
  calibrated.config.duty_clamp = options.law;
  calibrated.config.fixes.flow_feedback = trim;
  ClosedLoopRig rig = calibrated_rig(calibrated);
  const std::vector<double>& full = calibrated.full_flows;
  // The band's policy judged on the lines as the law sees them: with their held-open flows.
  std::vector<NozzleLine> lines = calibrated.lines;
  for (std::size_t i = 0; i < lines.size(); ++i) lines[i].full_open_flow_l_per_min = full[i];

  const std::size_t nozzles = full.size();
  sim::FieldDutyProcess field(nozzles, field_seed, options.field);
  std::vector<double> shares(nozzles), flows(nozzles, 0.0);
  apply_change(rig.plant(), change);
  rig.request_flows(flows);
  rig.start();
  rig.run_for(options.settle_s);

  std::vector<double> delivered0(nozzles);
  for (std::size_t i = 0; i < nozzles; ++i)
    delivered0[i] = rig.plant().nozzle_delivered_l(static_cast<int>(i));
  FieldDoseTally tally;
  AskedVolume asked;
  const double dt = options.request_period_s;
  for (double t = 0.0; t < options.run_s - 1e-9; t += dt) {
    const double step = std::min(dt, options.run_s - t);
    const double speed_factor = field.speed_factor_at(t);
    const double speed = options.law.nominal_speed_m_per_s * speed_factor;
    apply_change_progress(rig.plant(), change, t / options.run_s);
    rig.plant().set_ground_speed(speed);
    field.shares_at(t, shares);
    for (std::size_t i = 0; i < nozzles; ++i) {
      const AskedFlow flow = speed_following_flow(
          shares[i], full[i], options.law.nominal_speed_m_per_s, speed, full[i]);
      flows[i] = flow.flow_l_per_min;
      asked.add(flow, step);
      tally.add(options.law, lines[i], flows[i], options.pressure_mpa, speed, step);
    }
    rig.request_flows(flows);
    rig.run_for(step);
  }
  // The valves' last closing: what the last request sprays lands after it.
  std::fill(flows.begin(), flows.end(), 0.0);
  rig.request_flows(flows);
  rig.run_for(0.5);

  FieldDoseRun run;
  run.band_low_share = 0.0;
  run.band_high_share = 1.0;
  for (std::size_t i = 0; i < nozzles; ++i) {
    const double held = held_open_flow_l_per_min(lines[i], options.pressure_mpa);
    run.band_low_share = std::max(
        run.band_low_share,
        flow_for_duty_l_per_min(lines[i], options.law.min_duty_pct, options.pressure_mpa) / held);
    run.band_high_share = std::min(
        run.band_high_share,
        flow_for_duty_l_per_min(lines[i], options.law.max_duty_pct, options.pressure_mpa) / held);
  }
  for (std::size_t i = 0; i < nozzles; ++i)
    run.delivered_l += rig.plant().nozzle_delivered_l(static_cast<int>(i)) - delivered0[i];
  run.area_ha = tally.area_m2 / 1e4;
  run.target_l = tally.target_l;
  run.law_l = tally.law_l;
  if (run.area_ha > 0.0) {
    run.target_l_per_ha = run.target_l / run.area_ha;
    run.applied_l_per_ha = run.delivered_l / run.area_ha;
  }
  run.error_pct = percent_off(run.delivered_l, run.target_l);
  run.law_error_pct = percent_off(run.delivered_l, run.law_l);
  run.clipped_pct = asked.clipped_pct();
  if (tally.spraying_s > 0.0) {
    run.raised_share_pct = tally.raised_s / tally.spraying_s * 100.0;
    run.held_open_share_pct = tally.held_open_s / tally.spraying_s * 100.0;
  }
  return run;
}

FieldDoseFleetResult run_field_dose_fleet(const FleetOptions& fleet,
                                          const FieldDoseOptions& options) {
  FieldDoseFleetResult r;
  const std::vector<Machine> machines = draw_machines(fleet.seed, fleet.plants);
  for (std::size_t i = 0; i < machines.size(); ++i) {
    const int index = static_cast<int>(i);
    FieldDoseMachine m;
    m.change = fleet.changed ? draw_change(machines[i], fleet.seed, index) : no_change(machines[i]);
    const std::uint64_t field_seed = field_dose_seed(fleet.seed, index);
    m.trim_on = run_field_dose(machines[i], m.change, field_seed, true, options);
    m.trim_off = run_field_dose(machines[i], m.change, field_seed, false, options);
    r.machines.push_back(m);
  }
  const auto row = [&](FieldDoseRun FieldDoseMachine::*run) {
    std::vector<double> error, abs_error, law_error, raised, held, applied, clipped;
    for (const FieldDoseMachine& m : r.machines) {
      const FieldDoseRun& x = m.*run;
      error.push_back(x.error_pct);
      abs_error.push_back(std::abs(x.error_pct));
      law_error.push_back(x.law_error_pct);
      raised.push_back(x.raised_share_pct);
      held.push_back(x.held_open_share_pct);
      applied.push_back(x.applied_l_per_ha);
      clipped.push_back(x.clipped_pct);
    }
    return FieldDoseRow{signed_spread_of(error), spread_of(abs_error), signed_spread_of(law_error),
                        spread_of(raised),       spread_of(held),      spread_of(applied),
                        spread_of(clipped)};
  };
  r.trim_on = row(&FieldDoseMachine::trim_on);
  r.trim_off = row(&FieldDoseMachine::trim_off);
  return r;
}

}  // namespace weedspray::lab::experiments
