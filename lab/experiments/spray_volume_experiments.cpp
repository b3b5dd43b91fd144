// SPDX-License-Identifier: Apache-2.0
// Spray-volume accuracy: single-nozzle linearity (UGV Fig. 9) and the L16 orthogonal test
// (UGV Table 5 / Fig. 10), with the fixes or on the raw machine.
//
// "Requested" volume of a nozzle at duty d = d/100 x its full-open flow x run time. With the
// fixes the machine only knows its calibration, so the full-open flow it aims at is the
// calibrated line at 100 %; raw, there is no calibration and the reference is the nozzle's
// true full-open flow at the set-point. Either way the delivered volume is the TRUE one. A
// machine recalibrated after its change aims with the new calibration but is judged against
// the one as made, like every other row: the dose the job was set for does not move because
// a nozzle wore (judged against its own recalibration, a worn nozzle's extra flow would count
// as asked for).
//
// The duties are the demand at the reference speed (1 m/s, the speed the machine was calibrated
// and the L16 is laid out for). The drawn change ramps the ground speed (0.8-1.2 m/s), and a rate
// controller's target follows it: every control period each nozzle is asked its duty's share of
// the reference flow times speed / reference speed, through the daemon's rate law
// (speed_target.hpp), clipped at the reference's full-open flow. A nozzle at 100 % is asked
// the held-open flow at or above the reference speed and a share below it. The requested volume
// is the asked (clipped) target integrated over the run; what was clipped is reported apart.
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "lab/experiments/experiments.hpp"
#include "lab/experiments/rig_recheck.hpp"
#include "lab/experiments/speed_target.hpp"
#include "lab/experiments/vocabulary.hpp"

namespace weedspray::lab::experiments {
namespace {

struct PreparedMachine {
  RigConfig config;
  double pulses_per_litre = 0.0;  // the calibrated meter's
  std::vector<NozzleLine> lines;
  std::vector<double> full_flows;  // the full-open flow the machine knows per nozzle [L/min]
  // The requested reference per nozzle [L/min]: the flow a nozzle at 100 % is asked for and
  // judged against. The machine's knowledge but for a recalibration, which moves what the machine
  // knows and never the target: the job's dose was set by the calibration as made.
  std::vector<double> reference_flows;
};

PreparedMachine prepare_machine(const SprayRunOptions& options) {
  PreparedMachine m;
  m.config.seed = options.seed;
  m.config.setpoint_mpa = options.pressure_mpa;
  m.config.pwm_frequency_hz = options.frequency_hz;
  m.config.record_period_s = 0.0;
  m.config.plant = options.plant;
  m.config.ground_speed_m_per_s = options.reference_speed_m_per_s;
  if (options.raw) {
    m.config.fixes = {false, false, false};
    const plant::HydraulicPlant probe(m.config.plant, options.seed);  // as made
    for (int i = 0; i < probe.nozzle_count(); ++i)
      m.full_flows.push_back(probe.nozzle_full_open_flow_l_per_min(i, options.pressure_mpa));
    m.reference_flows = m.full_flows;
    return m;
  }
  CalibrationOptions cal_options;
  cal_options.seed = options.seed;
  cal_options.pressure_mpa = options.pressure_mpa;
  cal_options.frequency_hz = options.frequency_hz;
  cal_options.plant = options.plant;
  if (options.recalibrated) cal_options.change = options.change;
  const CalibrationResult& cal = cached_calibration(cal_options);
  m.config.fixes = {true, true, options.flow_feedback, options.model_trim};
  m.config.identify_nozzles = options.identify_nozzles;
  m.config.flow_trim = options.flow_trim;
  m.config.meter_pulses_per_l = cal.meter.pulses_per_litre;
  m.pulses_per_litre = cal.meter.pulses_per_litre;
  for (const auto& n : cal.nozzles) m.lines.push_back(n.fitted);
  m.full_flows = calibrated_full_flows(cal);
  m.reference_flows = m.full_flows;
  if (options.recalibrated) {
    cal_options.change.reset();
    m.reference_flows = calibrated_full_flows(cached_calibration(cal_options));
  }
  return m;
}

struct RunOutcome {
  std::vector<DutyPoint> nozzles;
  double pressure_band_mpa = 0.0;
  std::vector<double> identification_error_pct;  // options.identify_nozzles
};

// Each nozzle's target at the rig's ground speed now (options.follow_speed; else at the
// reference speed), clipped at the reference's full-open flow (the job's: a recalibration moves
// what the machine knows, not what it is asked), asked of the rig as flows. Raw, the machine has
// no rate law: its duties (shares of the true full-open flows) times speed / reference speed, at
// most 100 %, commanded again only when they move (a new command restarts the PWM's period).
struct SpeedFollowingRequest {
  const PreparedMachine& m;
  std::span<const double> duty_pct;
  const SprayRunOptions& options;
  std::vector<AskedFlow> asked = std::vector<AskedFlow>(duty_pct.size());
  std::vector<double> flows = std::vector<double>(duty_pct.size());
  std::vector<double> duties = std::vector<double>(duty_pct.size());
  bool commanded = false;

  void ask(ClosedLoopRig& rig) {
    const double reference = options.reference_speed_m_per_s;
    const double speed = options.follow_speed ? rig.plant().ground_speed_m_per_s() : reference;
    for (std::size_t i = 0; i < duty_pct.size(); ++i) {
      asked[i] = speed_following_flow(duty_pct[i] / 100.0, m.reference_flows[i], reference, speed,
                                      m.reference_flows[i]);
      flows[i] = asked[i].flow_l_per_min;
    }
    if (options.raw) {
      bool moved = !commanded;
      for (std::size_t i = 0; i < duty_pct.size(); ++i) {
        const double duty = std::min(100.0, duty_pct[i] * (speed / reference));
        moved = moved || duty != duties[i];
        duties[i] = duty;
      }
      if (moved) rig.command_duties(duties);
      commanded = true;
    } else {
      rig.request_flows(flows);
    }
  }
};

// One fresh run: start-up, settle, then run_s measured.
RunOutcome spray_run(const PreparedMachine& m, std::span<const double> duty_pct,
                     const SprayRunOptions& options) {
  ClosedLoopRig rig(m.config);
  const std::size_t n = duty_pct.size();
  if (!options.raw) {
    rig.set_nozzle_lines(m.lines);
    rig.set_full_open_flows(m.full_flows);
  }
  SpeedFollowingRequest request{m, duty_pct, options};
  if (options.change) apply_change(rig.plant(), *options.change);
  request.ask(rig);
  const std::vector<double>& flows = request.flows;
  rig.start();
  if (options.headland_recheck && !options.raw) {
    // The headland: every nozzle read alone, its line rescaled; the run's flows asked again as
    // it lets go (of the rescaled lines), then the run settles as any other.
    RigRecheckSettings settings{options.recheck_config, options.pressure_mpa,
                                options.recheck_pressure_tolerance_mpa};
    settings.config.interval_s = 0.0;
    RigRecheck recheck(settings, m.lines, m.full_flows, m.pulses_per_litre);
    const double limit_s = 10.0 * static_cast<double>(n) *
                           (options.recheck_config.settle_s + options.recheck_config.measure_s);
    recheck.run_whole_boom(rig, limit_s, [&] { rig.request_flows(flows); });
  }
  rig.run_for(options.settle_s);
  rig.restart_identification();
  std::vector<double> v0(n);
  for (std::size_t i = 0; i < n; ++i) v0[i] = rig.plant().nozzle_delivered_l(static_cast<int>(i));
  RunOutcome out;
  // Pressure band sampled every control period of the measured window; the targets follow the
  // ground speed at the same period.
  std::vector<AskedVolume> asked(n);
  const double dt = m.config.control_period_s;
  for (double t = 0.0; t < options.run_s - 1e-9; t += dt) {
    if (options.change) apply_change_progress(rig.plant(), *options.change, t / options.run_s);
    request.ask(rig);
    for (std::size_t i = 0; i < n; ++i) asked[i].add(request.asked[i], dt);
    rig.run_for(dt);
    out.pressure_band_mpa = std::max(
        out.pressure_band_mpa, std::abs(rig.plant().line_pressure_mpa() - options.pressure_mpa));
  }
  const auto duties = rig.commanded_duties_pct();
  for (std::size_t i = 0; i < n; ++i) {
    DutyPoint p;
    p.duty_pct = duty_pct[i];
    p.commanded_duty_pct = duties[i];
    p.requested_l = asked[i].asked_l;
    p.clipped_l = asked[i].clipped_l;
    p.delivered_l = rig.plant().nozzle_delivered_l(static_cast<int>(i)) - v0[i];
    p.error_pct =
        p.requested_l > 0 ? std::abs(p.delivered_l - p.requested_l) / p.requested_l * 100.0 : 0.0;
    out.nozzles.push_back(p);
    if (const PhaseWindowFit* fit = rig.nozzle_fit()) {
      const double truth = p.delivered_l / rig.identification_promised_l(static_cast<int>(i));
      out.identification_error_pct.push_back(std::abs(fit->ratio(i) / truth - 1.0) * 100.0);
    }
  }
  return out;
}

}  // namespace

LinearityResult run_linearity(const SprayRunOptions& options) {
  const PreparedMachine m = prepare_machine(options);
  LinearityResult result;
  result.raw = options.raw;
  std::vector<double> x, y;
  for (int d = 10; d <= 100; d += 10) {
    std::vector<double> duties(m.full_flows.size(), 100.0);
    duties[0] = d;
    const RunOutcome out = spray_run(m, duties, options);
    result.points.push_back(out.nozzles[0]);
    x.push_back(d);
    y.push_back(out.nozzles[0].delivered_l);
  }
  result.r2 = fit_line(x, y).r_squared;
  for (const auto& p : result.points) {
    result.mean_error_pct += p.error_pct / static_cast<double>(result.points.size());
    result.max_error_pct = std::max(result.max_error_pct, p.error_pct);
  }
  return result;
}

OrthogonalResult run_orthogonal(const SprayRunOptions& options) {
  const PreparedMachine m = prepare_machine(options);
  OrthogonalResult result;
  result.raw = options.raw;
  int count = 0;
  int identified = 0;
  double asked_l = 0.0, clipped_l = 0.0;
  for (const auto& row : kOrthogonalL16) {
    const RunOutcome out = spray_run(m, row, options);
    OrthogonalRun run;
    std::copy_n(out.nozzles.begin(), 4, run.nozzles.begin());
    run.pressure_band_mpa = out.pressure_band_mpa;
    for (std::size_t i = 0; i < out.identification_error_pct.size() && i < 4; ++i) {
      run.identification_error_pct[i] = out.identification_error_pct[i];
      if (run.nozzles[i].duty_pct >= 100.0) continue;
      result.mean_identification_error_pct += out.identification_error_pct[i];
      result.max_identification_error_pct =
          std::max(result.max_identification_error_pct, out.identification_error_pct[i]);
      ++identified;
    }
    for (const auto& p : run.nozzles) {
      asked_l += p.requested_l;
      clipped_l += p.clipped_l;
      result.mean_error_pct += p.error_pct;
      result.max_error_pct = std::max(result.max_error_pct, p.error_pct);
      if (p.duty_pct < 100.0)
        result.max_error_modulated_pct = std::max(result.max_error_modulated_pct, p.error_pct);
      ++count;
    }
    result.pressure_band_mpa = std::max(result.pressure_band_mpa, run.pressure_band_mpa);
    result.runs.push_back(run);
  }
  result.mean_error_pct /= count;
  if (identified > 0) result.mean_identification_error_pct /= identified;
  result.clipped_pct = AskedVolume{asked_l, clipped_l}.clipped_pct();
  return result;
}

double orthogonal_held_open_floor_pct(const SprayRunOptions& options) {
  const PreparedMachine m = prepare_machine(options);
  plant::HydraulicPlant changed(options.plant, options.seed);
  if (options.change) apply_change(changed, *options.change);
  const double p = options.pressure_mpa;
  const double band_mpa = 0.02;
  const double scale_lo = std::sqrt((p - band_mpa) / p);
  const double scale_hi = std::sqrt((p + band_mpa) / p);
  double floor_pct = 0.0;
  for (const auto& row : kOrthogonalL16) {
    double lo = 0.0, hi = 0.0;  // held-open flow / reference: lowest and highest
    for (std::size_t i = 0; i < row.size(); ++i) {
      if (row[i] < 100.0) continue;
      const double ratio =
          changed.nozzle_open_flow_now_l_per_min(static_cast<int>(i), p) / m.reference_flows[i];
      lo = lo == 0.0 ? ratio : std::min(lo, ratio);
      hi = std::max(hi, ratio);
    }
    if (hi == 0.0) continue;
    const double scale = std::clamp(2.0 / (lo + hi), scale_lo, scale_hi);
    const double worst = std::max(std::abs(scale * lo - 1.0), std::abs(scale * hi - 1.0));
    floor_pct = std::max(floor_pct, worst * 100.0);
  }
  return floor_pct;
}

double orthogonal_common_floor_pct(const SprayRunOptions& options) {
  const PreparedMachine m = prepare_machine(options);
  plant::HydraulicPlant changed(options.plant, options.seed);
  if (options.change) apply_change(changed, *options.change);
  const double p = options.pressure_mpa;
  const std::size_t n = m.full_flows.size();
  // Each nozzle's true flow over the reference, and as the drifted meter shows it (its drift
  // scales every reading alike: only a catch test sees it).
  const double drift = options.change ? options.change->meter_drift : 0.0;
  std::vector<double> ratio(n);
  for (std::size_t i = 0; i < n; ++i)
    ratio[i] =
        changed.nozzle_open_flow_now_l_per_min(static_cast<int>(i), p) / m.reference_flows[i];
  // The scale k in [lo, hi] (steps of 1e-4) minimising the summed |r (1 + drift) k - 1| of
  // `among` (what the meter shows), and the summed TRUE error |r k - 1| at that k.
  const auto true_error_at_best = [&](const std::vector<double>& among, double lo, double hi) {
    double best = 1e300, best_k = 1.0;
    for (double k = lo; k <= hi + 1e-12 && !among.empty(); k += 1e-4) {
      double sum = 0.0;
      for (const double r : among) sum += std::abs(r * (1.0 + drift) * k - 1.0);
      if (sum < best) best = sum, best_k = k;
    }
    double error = 0.0;
    for (const double r : among) error += std::abs(r * best_k - 1.0);
    return error;
  };
  const double band_mpa = 0.02;
  double total = 0.0;
  int count = 0;
  for (const auto& row : kOrthogonalL16) {
    std::vector<double> held, modulated;
    for (std::size_t i = 0; i < n && i < row.size(); ++i)
      (row[i] >= 100.0 ? held : modulated).push_back(ratio[i]);
    // Held open: only the pressure, within the band; modulated: one common factor.
    total +=
        true_error_at_best(held, std::sqrt((p - band_mpa) / p), std::sqrt((p + band_mpa) / p)) +
        true_error_at_best(modulated, 0.7, 1.3);
    count += static_cast<int>(held.size() + modulated.size());
  }
  return count > 0 ? total / count * 100.0 : 0.0;
}

}  // namespace weedspray::lab::experiments

namespace weedspray::lab::experiments {
namespace {

// The q-quantile of `values` (linear between the two nearest ranks).
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double at = q * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(at));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (at - static_cast<double>(lo)) * (values[hi] - values[lo]);
}

OrthogonalFleetRow summarise(std::vector<OrthogonalResult> machines) {
  std::vector<double> mean, max, max_modulated, band, id_mean, id_max, nozzle_runs, clipped;
  for (const auto& r : machines) {
    clipped.push_back(r.clipped_pct);
    for (const auto& run : r.runs)
      for (const auto& p : run.nozzles) nozzle_runs.push_back(p.error_pct);
    mean.push_back(r.mean_error_pct);
    max.push_back(r.max_error_pct);
    max_modulated.push_back(r.max_error_modulated_pct);
    band.push_back(r.pressure_band_mpa);
    id_mean.push_back(r.mean_identification_error_pct);
    id_max.push_back(r.max_identification_error_pct);
  }
  OrthogonalFleetRow row;
  row.mean_error_pct = spread_of(mean);
  row.max_error_pct = spread_of(max);
  row.max_error_modulated_pct = spread_of(max_modulated);
  row.pressure_band_mpa = spread_of(band);
  row.mean_identification_error_pct = spread_of(id_mean);
  row.max_identification_error_pct = spread_of(id_max);
  row.per_nozzle_mean_error_pct = spread_of(nozzle_runs).mean;
  row.per_nozzle_p95_error_pct = quantile(std::move(nozzle_runs), 0.95);
  row.clipped_pct = spread_of(clipped);
  row.machines = std::move(machines);
  return row;
}

}  // namespace

LinearityFleetResult run_linearity_fleet(const FleetOptions& fleet, const SprayRunOptions& base) {
  std::vector<double> r2, mean, max;
  const std::vector<Machine> machines = draw_machines(fleet.seed, fleet.plants);
  for (std::size_t i = 0; i < machines.size(); ++i) {
    SprayRunOptions options = base;
    options.seed = machines[i].seed;
    options.plant = machines[i].params;
    options.raw = false;
    options.change = fleet.changed ? draw_change(machines[i], fleet.seed, static_cast<int>(i))
                                   : no_change(machines[i]);
    const LinearityResult r = run_linearity(options);
    r2.push_back(r.r2);
    mean.push_back(r.mean_error_pct);
    max.push_back(r.max_error_pct);
  }
  return {spread_of(r2, true), spread_of(mean), spread_of(max)};
}

OrthogonalFleetResult run_orthogonal_fleet(const FleetOptions& fleet, const SprayRunOptions& base) {
  std::vector<OrthogonalResult> on, model, off, recalibrated, rechecked;
  std::vector<double> held_open_floor, common_floor;
  double speed_min = std::numeric_limits<double>::infinity(), speed_max = -speed_min;
  const std::vector<Machine> machines = draw_machines(fleet.seed, fleet.plants);
  for (std::size_t i = 0; i < machines.size(); ++i) {
    const Machine& m = machines[i];
    SprayRunOptions options = base;
    options.seed = m.seed;
    options.plant = m.params;
    options.raw = false;
    options.change = fleet.changed
                         ? draw_change_parts(m, fleet.seed, static_cast<int>(i), fleet.parts)
                         : no_change(m);
    for (const double speed :
         {options.change->speed_start_m_per_s, options.change->speed_end_m_per_s}) {
      speed_min = std::min(speed_min, speed);
      speed_max = std::max(speed_max, speed);
    }
    options.flow_feedback = true;
    options.model_trim = false;
    held_open_floor.push_back(orthogonal_held_open_floor_pct(options));
    common_floor.push_back(orthogonal_common_floor_pct(options));
    on.push_back(run_orthogonal(options));
    // The diagnostic in a pass of its own: its phase windows split the plant's steps, which
    // draws the plant's noise differently, so the row above stays the daemon's trim alone.
    options.identify_nozzles = true;
    const OrthogonalResult identified = run_orthogonal(options);
    on.back().mean_identification_error_pct = identified.mean_identification_error_pct;
    on.back().max_identification_error_pct = identified.max_identification_error_pct;
    options.identify_nozzles = false;
    options.model_trim = true;
    model.push_back(run_orthogonal(options));
    options.model_trim = false;
    options.flow_feedback = false;
    off.push_back(run_orthogonal(options));
    options.flow_feedback = true;
    options.headland_recheck = true;
    rechecked.push_back(run_orthogonal(options));
    options.headland_recheck = false;
    options.recalibrated = true;
    recalibrated.push_back(run_orthogonal(options));
  }
  OrthogonalFleetResult result;
  result.trim_on = summarise(std::move(on));
  result.model_trim = summarise(std::move(model));
  result.trim_off = summarise(std::move(off));
  result.recalibrated = summarise(std::move(recalibrated));
  result.headland_recheck = summarise(std::move(rechecked));
  result.held_open_floor_pct = spread_of(held_open_floor);
  result.common_floor_pct = spread_of(common_floor);
  result.speed_min_m_per_s = machines.empty() ? base.reference_speed_m_per_s : speed_min;
  result.speed_max_m_per_s = machines.empty() ? base.reference_speed_m_per_s : speed_max;
  return result;
}

}  // namespace weedspray::lab::experiments
