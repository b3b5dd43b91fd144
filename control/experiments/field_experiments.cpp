// The wheat paper's field-side checks: delivered vs theoretical flow over weed densities
// (dose), and liquid saved by variable vs uniform spraying over a field (savings).
// Both use the spray-rate law of control/spray_rate_law.hpp on a machine calibrated at the
// wheat paper's operating point (0.4 MPa, 5 Hz).
#include <algorithm>
#include <cmath>
#include <vector>

#include "control/experiments/experiments.hpp"

namespace weedspray::control::experiments {
namespace {

struct CalibratedMachine {
  RigConfig config;
  std::vector<NozzleLine> lines;
  std::vector<double> full_flows;
};

CalibratedMachine calibrate(std::uint64_t seed, double pressure_mpa, double frequency_hz,
                            const SprayLawConfig& law) {
  CalibrationOptions cal_options;
  cal_options.seed = seed;
  cal_options.pressure_mpa = pressure_mpa;
  cal_options.frequency_hz = frequency_hz;
  const CalibrationResult cal = run_calibration(cal_options);
  CalibratedMachine m;
  m.config.seed = seed;
  m.config.setpoint_mpa = pressure_mpa;
  m.config.pwm_frequency_hz = frequency_hz;
  m.config.record_period_s = 0.0;
  m.config.meter_pulses_per_l = cal.meter.pulses_per_litre;
  m.config.duty_clamp = law;
  for (const auto& n : cal.nozzles) m.lines.push_back(n.fitted);
  m.full_flows = calibrated_full_flows(cal);
  return m;
}

ClosedLoopRig make_rig(const CalibratedMachine& m) {
  ClosedLoopRig rig(m.config);
  rig.set_nozzle_lines(m.lines);
  rig.set_full_open_flows(m.full_flows);
  return rig;
}

}  // namespace

DoseResult run_dose(const DoseOptions& options) {
  SprayLawConfig law;
  law.max_density = options.max_density;
  const CalibratedMachine m =
      calibrate(options.seed, options.pressure_mpa, options.frequency_hz, law);
  DoseResult result;
  std::vector<double> x, y;
  for (double density : options.densities) {
    ClosedLoopRig rig = make_rig(m);
    const double q = target_flow_l_per_min(law, density, options.speed_m_per_s);
    rig.request_flows(std::vector<double>(m.full_flows.size(), q));
    rig.start();
    rig.run_for(options.settle_s);
    const double v0 = rig.plant().nozzle_delivered_l(0);
    rig.run_for(options.run_s);
    DosePoint p;
    p.density = density;
    p.theoretical_l_per_min = q;
    p.delivered_l_per_min = (rig.plant().nozzle_delivered_l(0) - v0) / (options.run_s / 60.0);
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

SavingsResult run_savings(const std::vector<std::array<double, 4>>& zone_densities,
                          const SavingsOptions& options) {
  SprayLawConfig law;
  law.max_density = options.max_density;
  law.decision_threshold = options.decision_threshold;
  const CalibratedMachine m =
      calibrate(options.seed, options.pressure_mpa, options.frequency_hz, law);
  const std::size_t nozzles = std::min<std::size_t>(4, m.full_flows.size());
  const double zone_s = options.zone_length_m / options.speed_m_per_s;
  SavingsResult result;
  result.zones = static_cast<int>(zone_densities.size() * nozzles);

  // Uniform spraying: every nozzle at the nominal flow q_nom over the whole track, which is
  // the flow the law gives the densest zone (D = k).
  const double uniform_q = target_flow_l_per_min(law, law.max_density, options.speed_m_per_s);
  std::array<double, 4> uniform_per_nozzle{};
  {
    ClosedLoopRig rig = make_rig(m);
    rig.request_flows(std::vector<double>(nozzles, uniform_q));
    rig.start();
    rig.run_for(3.0);  // start-up before the first zone
    std::array<double, 4> v0{};
    for (std::size_t i = 0; i < nozzles; ++i) v0[i] = rig.plant().nozzle_delivered_l(int(i));
    rig.run_for(zone_s * static_cast<double>(zone_densities.size()));
    for (std::size_t i = 0; i < nozzles; ++i) {
      uniform_per_nozzle[i] = rig.plant().nozzle_delivered_l(int(i)) - v0[i];
      result.uniform_l += uniform_per_nozzle[i];
    }
  }

  // Variable spraying: each zone's decision applied while that zone passes under the nozzles
  // (ideal distance scheduling; the PWM still latches duties only at period boundaries).
  ClosedLoopRig rig = make_rig(m);
  rig.request_flows(std::vector<double>(nozzles, 0.0));
  rig.start();
  rig.run_for(3.0);
  std::array<double, 4> variable_per_nozzle{};
  for (const auto& zone : zone_densities) {
    std::vector<double> flows(nozzles);
    double target_l = 0.0;
    std::vector<double> targets(nozzles);
    for (std::size_t i = 0; i < nozzles; ++i) {
      flows[i] = target_flow_l_per_min(law, zone[i], options.speed_m_per_s);
      // What the law decided for this zone: nothing below the minimum duty, the full-open
      // flow above the maximum. Weedy zones the clamp leaves dry are counted apart.
      const SprayDecision decision =
          spray_decision(law, m.lines[i], zone[i], options.speed_m_per_s, options.pressure_mpa);
      targets[i] = decision.duty_pct <= 0.0     ? 0.0
                   : decision.duty_pct >= 100.0 ? m.full_flows[i]
                                                : flows[i];
      if (flows[i] > 0.0 && targets[i] == 0.0) ++result.unsprayed_weedy_zones;
      target_l += targets[i] * zone_s / 60.0;
    }
    std::array<double, 4> v0{};
    for (std::size_t i = 0; i < nozzles; ++i) v0[i] = rig.plant().nozzle_delivered_l(int(i));
    rig.request_flows(flows);
    rig.run_for(zone_s);
    double delivered_l = 0.0;
    for (std::size_t i = 0; i < nozzles; ++i) {
      const double d = rig.plant().nozzle_delivered_l(int(i)) - v0[i];
      variable_per_nozzle[i] += d;
      delivered_l += d;
      const double target = targets[i] * zone_s / 60.0;
      if (target > 0.0 && d < options.under_dose_fraction * target) ++result.under_dosed_zones;
    }
    result.zone_target_l.push_back(target_l);
    result.zone_delivered_l.push_back(delivered_l);
    result.variable_l += delivered_l;
  }
  result.savings_pct =
      result.uniform_l > 0 ? (1.0 - result.variable_l / result.uniform_l) * 100.0 : 0.0;
  for (std::size_t i = 0; i < nozzles; ++i)
    result.nozzle_savings_pct[i] =
        uniform_per_nozzle[i] > 0 ? (1.0 - variable_per_nozzle[i] / uniform_per_nozzle[i]) * 100.0
                                  : 0.0;
  return result;
}

}  // namespace weedspray::control::experiments
