// SPDX-License-Identifier: Apache-2.0
#include "sim/plant/hydraulic_plant.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace weedspray::sim::plant {
namespace {

void require(bool ok, const char* name, const char* rule) {
  if (!ok) throw std::invalid_argument(std::string("PlantParams.") + name + " must be " + rule);
}

void validate(const PlantParams& p) {
  require(p.nozzle_count >= 1 && p.nozzle_count <= kMaxNozzles, "nozzle_count", "in [1, 8]");
  require(p.pump.open_flow_l_per_min > 0, "pump.open_flow_l_per_min", "> 0");
  require(p.pump.shutoff_pressure_mpa > 0, "pump.shutoff_pressure_mpa", "> 0");
  require(p.pump.spin_time_constant_s > 0, "pump.spin_time_constant_s", "> 0");
  require(p.return_valve.full_scale_volts > p.return_valve.dead_band_volts &&
              p.return_valve.dead_band_volts >= 0,
          "return_valve.full_scale_volts", "> dead_band_volts >= 0");
  require(p.return_valve.k_l_per_min_sqrt_mpa > 0, "return_valve.k_l_per_min_sqrt_mpa", "> 0");
  require(p.return_valve.time_constant_s > 0, "return_valve.time_constant_s", "> 0");
  require(p.line.hose_compliance_l_per_mpa > 0, "line.hose_compliance_l_per_mpa", "> 0");
  require(p.line.air_chamber_volume_l >= 0, "line.air_chamber_volume_l", ">= 0");
  require(p.line.air_chamber_precharge_mpa >= 0, "line.air_chamber_precharge_mpa", ">= 0");
  require(p.line.laminar_below_mpa > 0, "line.laminar_below_mpa", "> 0");
  require(p.nozzle.k_l_per_min_sqrt_mpa > 0, "nozzle.k_l_per_min_sqrt_mpa", "> 0");
  require(p.nozzle.k_spread_sigma >= 0 && p.nozzle.k_spread_sigma < 0.2, "nozzle.k_spread_sigma",
          "in [0, 0.2)");
  require(p.nozzle.open_delay_s >= 0 && p.nozzle.close_delay_s >= 0, "nozzle.*_delay_s", ">= 0");
  require(p.nozzle.open_travel_s > 0 && p.nozzle.close_travel_s > 0, "nozzle.*_travel_s", "> 0");
  require(p.nozzle.delay_spread_sigma >= 0 && p.nozzle.delay_spread_sigma < 0.3,
          "nozzle.delay_spread_sigma", "in [0, 0.3)");
  require(p.pressure_sensor.full_scale_mpa > 0, "pressure_sensor.full_scale_mpa", "> 0");
  require(p.pressure_sensor.shunt_ohms > 0, "pressure_sensor.shunt_ohms", "> 0");
  require(p.pressure_sensor.noise_volts_sigma >= 0, "pressure_sensor.noise_volts_sigma", ">= 0");
  require(p.pressure_sensor.time_constant_s >= 0, "pressure_sensor.time_constant_s", ">= 0");
  require(std::abs(p.pressure_sensor.offset_fraction) < 0.25, "pressure_sensor.offset_fraction",
          "within +-0.25");
  require(p.pressure_sensor.span_error > -1, "pressure_sensor.span_error", "> -1");
  require(std::isfinite(p.pressure_sensor.drift_per_hour), "pressure_sensor.drift_per_hour",
          "finite");
  require(p.flow_meter.nominal_pulses_per_l > 0, "flow_meter.nominal_pulses_per_l", "> 0");
  require(p.flow_meter.k_factor_error > -0.5 && p.flow_meter.k_factor_error < 0.5,
          "flow_meter.k_factor_error", "in (-0.5, 0.5)");
  require(p.wheel.nominal_pulses_per_m > 0, "wheel.nominal_pulses_per_m", "> 0");
  require(p.wheel.circumference_error > -0.5 && p.wheel.circumference_error < 0.5,
          "wheel.circumference_error", "in (-0.5, 0.5)");
  require(p.tank.capacity_l > 0, "tank.capacity_l", "> 0");
  require(p.tank.initial_level_l >= 0 && p.tank.initial_level_l <= p.tank.capacity_l,
          "tank.initial_level_l", "in [0, capacity_l]");
  require(p.tank.suction_loss_below_l > 0, "tank.suction_loss_below_l", "> 0");
  require(p.pump.chambers >= 0 && p.pump.chambers <= 8, "pump.chambers", "in [0, 8]");
  require(p.pump.rated_rpm > 0, "pump.rated_rpm", "> 0");
  require(p.pump.nominal_supply_volts > 0 && p.pump.supply_volts >= 0, "pump.*supply_volts",
          "> 0 (nominal), >= 0");
  require(p.pump.load_speed_sag >= 0 && p.pump.load_speed_sag < 1, "pump.load_speed_sag",
          "in [0, 1)");
  require(p.boom.inertance_mpa_s2_per_l >= 0, "boom.inertance_mpa_s2_per_l", ">= 0");
  require(p.boom.friction_mpa_per_l_per_s_sq >= 0, "boom.friction_mpa_per_l_per_s_sq", ">= 0");
  require(p.boom.boom_compliance_l_per_mpa > 0, "boom.boom_compliance_l_per_mpa", "> 0");
  require(p.boom.section_loss_mpa_per_l_per_s_sq >= 0, "boom.section_loss_mpa_per_l_per_s_sq",
          ">= 0");
  require(p.boom.valve_k_l_per_min_sqrt_mpa >= 0, "boom.valve_k_l_per_min_sqrt_mpa", ">= 0");
  require(p.boom.valve_k_spread_sigma >= 0 && p.boom.valve_k_spread_sigma < 0.3,
          "boom.valve_k_spread_sigma", "in [0, 0.3)");
  require(p.nozzle.travel_spread_sigma >= 0 && p.nozzle.travel_spread_sigma < 0.3,
          "nozzle.travel_spread_sigma", "in [0, 0.3)");
  require(p.nozzle.delay_drift_per_hour_sigma >= 0, "nozzle.delay_drift_per_hour_sigma", ">= 0");
  require(p.flow_meter.low_flow_error >= 0 && p.flow_meter.low_flow_error < 0.5,
          "flow_meter.low_flow_error", "in [0, 0.5)");
  require(p.flow_meter.low_flow_knee_l_per_min > 0, "flow_meter.low_flow_knee_l_per_min", "> 0");
  require(p.flow_meter.pulse_jitter >= 0 && p.flow_meter.pulse_jitter < 0.5,
          "flow_meter.pulse_jitter", "in [0, 0.5)");
  require(p.wheel.slip > -0.5 && p.wheel.slip < 0.5, "wheel.slip", "in (-0.5, 0.5)");
  require(p.integration_step_s > 0 && p.integration_step_s <= 1e-3, "integration_step_s",
          "in (0, 1e-3] (>= 1 kHz)");
}

double clipped_factor(std::mt19937_64& rng, std::normal_distribution<double>& unit_normal,
                      double sigma) {
  const double z = std::clamp(unit_normal(rng), -2.5, 2.5);
  return 1.0 + sigma * z;
}

// Mean of a quantity moving linearly from `from` toward `to` at `rate` per second, starting
// at `start` (relative to the interval [0, dt]); returns {mean, end value}. Exact, so a
// valve's delivered volume does not depend on where the integration steps fall.
std::pair<double, double> ramp_mean_and_end(double from, double to, double rate, double start,
                                            double dt) {
  if (from == to || start >= dt) return {from, from};
  const double lead = std::max(start, 0.0);
  const double travel_time = std::abs(to - from) / rate;
  const double moving = std::min(travel_time, dt - lead);
  const double dir = to > from ? 1.0 : -1.0;
  // A move that runs its whole travel ends on its target exactly: from + rate * (|to - from| /
  // rate) can miss it by a rounding error, and a valve then never quite closes.
  const double end_of_move = moving >= travel_time ? to : from + dir * rate * moving;
  const double hold = dt - lead - moving;
  const double integral = from * lead + 0.5 * (from + end_of_move) * moving + end_of_move * hold;
  return {integral / dt, end_of_move};
}

// Outlet flow of an n-chamber single-acting pump at shaft angle theta, relative to its mean:
// (pi / n) sum_k max(0, sin(theta - 2 pi k / n)); the mean of each half-sine is 1 / pi.
double pulsation_factor(int chambers, double theta) {
  if (chambers <= 0) return 1.0;
  constexpr double kPi = 3.14159265358979323846;
  double sum = 0.0;
  for (int k = 0; k < chambers; ++k)
    sum += std::max(0.0, std::sin(theta - 2.0 * kPi * k / chambers));
  return kPi / chambers * sum;
}

}  // namespace

PlantParams realistic_plant_params() {
  PlantParams p;
  p.pump.chambers = 3;
  p.pump.load_speed_sag = 0.2;
  p.boom.inertance_mpa_s2_per_l = 0.038;
  p.boom.friction_mpa_per_l_per_s_sq = 0.9;
  p.boom.section_loss_mpa_per_l_per_s_sq = 0.3;
  p.boom.valve_k_l_per_min_sqrt_mpa = 7.9;
  p.boom.valve_k_spread_sigma = 0.10;
  p.nozzle.travel_spread_sigma = 0.15;
  p.nozzle.delay_drift_per_hour_sigma = 0.05;
  p.flow_meter.low_flow_error = 0.15;
  p.flow_meter.pulse_jitter = 0.3;
  p.wheel.slip = 0.02;
  return p;
}

HydraulicPlant::HydraulicPlant(const PlantParams& params, std::uint64_t seed)
    : params_(params), rng_(seed), realism_rng_(seed ^ 0x9e3779b97f4a7c15ULL) {
  validate(params_);
  for (int i = 0; i < params_.nozzle_count; ++i) {
    NozzleTruth& t = truth_[static_cast<std::size_t>(i)];
    t.k_l_per_min_sqrt_mpa = params_.nozzle.k_l_per_min_sqrt_mpa *
                             clipped_factor(rng_, unit_normal_, params_.nozzle.k_spread_sigma);
    t.open_delay_s = params_.nozzle.open_delay_s *
                     clipped_factor(rng_, unit_normal_, params_.nozzle.delay_spread_sigma);
    t.close_delay_s = params_.nozzle.close_delay_s *
                      clipped_factor(rng_, unit_normal_, params_.nozzle.delay_spread_sigma);
  }
  for (int i = 0; i < params_.nozzle_count; ++i) {
    NozzleTruth& t = truth_[static_cast<std::size_t>(i)];
    const double travel =
        clipped_factor(realism_rng_, realism_normal_, params_.nozzle.travel_spread_sigma);
    t.open_travel_s = params_.nozzle.open_travel_s * travel;
    t.close_travel_s = params_.nozzle.close_travel_s * travel;
    t.valve_k_l_per_min_sqrt_mpa =
        params_.boom.valve_k_l_per_min_sqrt_mpa *
        clipped_factor(realism_rng_, realism_normal_, params_.boom.valve_k_spread_sigma);
    t.delay_drift_per_hour = params_.nozzle.delay_drift_per_hour_sigma *
                             std::clamp(realism_normal_(realism_rng_), -2.5, 2.5);
  }
  tank_level_l_ = params_.tank.initial_level_l;
  supply_volts_ = params_.pump.supply_volts;
  wheel_slip_ = params_.wheel.slip;
  std::uniform_real_distribution<double> jitter(-params_.flow_meter.pulse_jitter,
                                                params_.flow_meter.pulse_jitter);
  next_pulse_at_ = 1.0 + jitter(realism_rng_);
}

double HydraulicPlant::delay_scale(int i) const {
  const auto& v = valves_[static_cast<std::size_t>(i)];
  const double drift =
      1.0 + truth_[static_cast<std::size_t>(i)].delay_drift_per_hour * time_s_ / 3600.0;
  return v.ageing * std::max(0.1, drift);
}

double HydraulicPlant::series_k(int i) const {
  const auto& v = valves_[static_cast<std::size_t>(i)];
  const NozzleTruth& t = truth_[static_cast<std::size_t>(i)];
  const double kn = t.k_l_per_min_sqrt_mpa * (1.0 + v.wear) * (1.0 - v.blockage);
  const double kv = t.valve_k_l_per_min_sqrt_mpa;
  if (kv <= 0.0 || kn <= 0.0) return kn;
  // Two orifices in series: 1 / k^2 = 1 / kn^2 + 1 / kv^2.
  return kn * kv / std::sqrt(kn * kn + kv * kv);
}

double HydraulicPlant::pump_rpm() const {
  const auto& pp = params_.pump;
  const double load = std::clamp(pressure_mpa_ / pp.shutoff_pressure_mpa, 0.0, 1.0);
  return pp.rated_rpm * pump_speed_ * supply_volts_ / pp.nominal_supply_volts *
         (1.0 - pp.load_speed_sag * load);
}

double HydraulicPlant::metered_pulses_per_l(double line_flow_l_per_s) const {
  const auto& m = params_.flow_meter;
  const double q = std::abs(line_flow_l_per_s) * 60.0;
  const double low =
      m.low_flow_error > 0.0 ? m.low_flow_error * std::exp(-q / m.low_flow_knee_l_per_min) : 0.0;
  return true_meter_pulses_per_l() * (1.0 - low);
}

void HydraulicPlant::set_pump(bool on) {
  pump_on_ = on;
}

void HydraulicPlant::set_return_valve_volts(double volts) {
  return_volts_ = std::clamp(volts, 0.0, params_.return_valve.full_scale_volts);
}

void HydraulicPlant::set_valves(std::uint32_t mask) {
  valve_mask_ = mask;
  for (int i = 0; i < params_.nozzle_count; ++i) {
    Valve& v = valves_[static_cast<std::size_t>(i)];
    const bool cmd = ((mask >> i) & 1U) != 0 || v.stuck_open;
    if (cmd == v.commanded) continue;
    v.commanded = cmd;
    const NozzleTruth& t = truth_[static_cast<std::size_t>(i)];
    // Only a spool already travelling coasts on; a motion whose dead time had not ended is
    // cancelled (the coil never pulled in / dropped out).
    const bool travelling = v.motion_start_s <= time_s_ && v.position != v.motion_target;
    v.coast_target = travelling ? v.motion_target : v.position;
    v.motion_target = cmd ? 1.0 : 0.0;
    v.motion_start_s = time_s_ + (cmd ? t.open_delay_s : t.close_delay_s) * delay_scale(i);
  }
}

void HydraulicPlant::set_ground_speed(double m_per_s) {
  speed_m_per_s_ = std::max(0.0, m_per_s);
}

void HydraulicPlant::step(double dt_s) {
  if (!(dt_s >= 0.0)) throw std::invalid_argument("HydraulicPlant::step: dt_s must be >= 0");
  const double h = params_.integration_step_s;
  double remaining = dt_s;
  while (remaining > 1e-12) {
    const double dt = std::min(h, remaining);
    substep(dt);
    remaining -= dt;
  }
  sensor_noise_volts_ = params_.pressure_sensor.noise_volts_sigma * unit_normal_(rng_);
}

double HydraulicPlant::orifice_flow_l_per_s(double k_l_per_min, double pressure_mpa) const {
  const double p = std::max(pressure_mpa, 0.0);
  const double pl = params_.line.laminar_below_mpa;
  const double q = p >= pl ? k_l_per_min * std::sqrt(p) : k_l_per_min * p / std::sqrt(pl);
  return q / 60.0;
}

double HydraulicPlant::line_compliance_l_per_mpa(double pressure_mpa) const {
  double c = params_.line.hose_compliance_l_per_mpa;
  const double v0 = params_.line.air_chamber_volume_l;
  if (v0 > 0.0) {
    // Isothermal gas: V = V0 * P0abs / Pabs above the precharge, so dV/dP = V0 P0abs / Pabs^2.
    // Below the precharge the membrane rests on its seat and the chamber takes no liquid.
    constexpr double kAtmosphereMpa = 0.101325;
    const double p0 = params_.line.air_chamber_precharge_mpa + kAtmosphereMpa;
    const double pabs = std::max(pressure_mpa, 0.0) + kAtmosphereMpa;
    if (pabs > p0) c += v0 * p0 / (pabs * pabs);
  }
  return c;
}

double HydraulicPlant::advance_valve(Valve& v, double t0, double dt) const {
  const auto i = static_cast<std::size_t>(&v - valves_.data());
  const NozzleTruth& t = truth_[i];
  // Travel from the drawn per-valve times (0 drawn = the params' value: ideal bench).
  const double open_s =
      (t.open_travel_s > 0 ? t.open_travel_s : params_.nozzle.open_travel_s) * v.ageing;
  const double close_s =
      (t.close_travel_s > 0 ? t.close_travel_s : params_.nozzle.close_travel_s) * v.ageing;
  auto rate_toward = [&](double target) {
    return target > v.position ? 1.0 / open_s : 1.0 / close_s;
  };
  const bool coasting = v.motion_start_s > t0 && v.coast_target != v.position;
  if (!coasting) {
    const auto [mean, end] = ramp_mean_and_end(
        v.position, v.motion_target, rate_toward(v.motion_target), v.motion_start_s - t0, dt);
    v.position = std::clamp(end, 0.0, 1.0);
    return mean;
  }
  // Coasting toward the old end until the new motion starts, then the new motion.
  const double span = std::min(dt, v.motion_start_s - t0);
  const auto [coast_mean, coast_end] =
      ramp_mean_and_end(v.position, v.coast_target, rate_toward(v.coast_target), 0.0, span);
  v.position = std::clamp(coast_end, 0.0, 1.0);
  const double rest = dt - span;
  if (!(rest > 0.0)) return coast_mean;
  const auto [mean, end] =
      ramp_mean_and_end(v.position, v.motion_target, rate_toward(v.motion_target), 0.0, rest);
  v.position = std::clamp(end, 0.0, 1.0);
  return (coast_mean * span + mean * rest) / dt;
}

void HydraulicPlant::substep(double dt) {
  const double t0 = time_s_;
  const double p = pressure_mpa_;
  const auto& pp = params_.pump;

  // Pump: motor speed lags the relay; flow falls linearly with pressure to shut-off and scales
  // with supply voltage; a blocked filter or an almost empty tank starves it; an n-chamber
  // pump delivers it in pulses.
  const double speed_target = pump_on_ ? 1.0 : 0.0;
  pump_speed_ += (speed_target - pump_speed_) * (1.0 - std::exp(-dt / pp.spin_time_constant_s));
  const double curve = std::max(0.0, 1.0 - p / pp.shutoff_pressure_mpa);
  const double suction = std::clamp(tank_level_l_ / params_.tank.suction_loss_below_l, 0.0, 1.0);
  const double volts = supply_volts_ / pp.nominal_supply_volts;
  double pulsation = 1.0;
  if (pp.chambers > 0) {
    constexpr double kTwoPi = 6.28318530717958647692;
    pump_angle_rad_ = std::fmod(pump_angle_rad_ + pump_rpm() / 60.0 * kTwoPi * dt, kTwoPi);
    pulsation = pulsation_factor(pp.chambers, pump_angle_rad_);
  }
  pump_flow_l_per_s_ = pump_speed_ * pp.open_flow_l_per_min / 60.0 * curve * volts *
                       (1.0 - filter_blockage_) * suction * pulsation;

  // Return valve: first-order lag toward the commanded opening.
  const auto& rv = params_.return_valve;
  const double open_cmd = std::clamp(
      (return_volts_ - rv.dead_band_volts) / (rv.full_scale_volts - rv.dead_band_volts), 0.0, 1.0);
  return_opening_ += (open_cmd - return_opening_) * (1.0 - std::exp(-dt / rv.time_constant_s));
  return_flow_l_per_s_ = orifice_flow_l_per_s(rv.k_l_per_min_sqrt_mpa * return_opening_, p);

  // Nozzles along the boom: each tap sees the boom pressure less the section losses up to it
  // (flows of the previous sub-step: the losses are small and slow next to the step).
  const bool inertia = inertance_on();
  const double boom_p = inertia ? boom_pressure_mpa_ : p;
  const double r_section = params_.boom.section_loss_mpa_per_l_per_s_sq;
  double downstream = 0.0;
  if (r_section > 0.0)
    for (int i = 0; i < params_.nozzle_count; ++i)
      downstream += valves_[static_cast<std::size_t>(i)].flow_l_per_s;
  double tap_p = boom_p;
  double nozzle_flow = 0.0;
  for (int i = 0; i < params_.nozzle_count; ++i) {
    Valve& v = valves_[static_cast<std::size_t>(i)];
    if (r_section > 0.0 && i > 0) tap_p -= r_section * downstream * downstream;
    const bool was_open = v.position >= 0.5;
    const double opening = advance_valve(v, t0, dt);
    if (record_crossings_ && was_open != (v.position >= 0.5))
      crossings_.push_back({i, v.position >= 0.5, t0 + dt, distance_m_ + speed_m_per_s_ * dt});
    const double previous = v.flow_l_per_s;
    v.flow_l_per_s = orifice_flow_l_per_s(series_k(i) * opening, tap_p);
    v.delivered_l += v.flow_l_per_s * dt;
    nozzle_flow += v.flow_l_per_s;
    downstream -= previous;
  }

  // Pressures: volume balance on the compliances. With inertance the feed hose's flow is a
  // state (L dq/dt = P - P_boom - R q|q|), updated first (semi-implicit Euler: stable for the
  // hose's LC resonance at this step).
  double line_flow = nozzle_flow;
  if (inertia) {
    const auto& b = params_.boom;
    const double q = line_flow_l_per_s_;
    line_flow_l_per_s_ +=
        (p - boom_pressure_mpa_ - b.friction_mpa_per_l_per_s_sq * q * std::abs(q)) * dt /
        b.inertance_mpa_s2_per_l;
    line_flow = line_flow_l_per_s_;
    boom_pressure_mpa_ = std::max(
        0.0, boom_pressure_mpa_ + (line_flow - nozzle_flow) * dt / b.boom_compliance_l_per_mpa);
  }
  const double dp =
      (pump_flow_l_per_s_ - return_flow_l_per_s_ - line_flow) * dt / line_compliance_l_per_mpa(p);
  pressure_mpa_ = std::max(0.0, p + dp);

  // The flow meter sits in the feed line: it sees the nozzles' total flow (the hose's flow
  // with inertance), under-reads at low flow and places each pulse edge with some jitter.
  metered_l_ += line_flow * dt;
  meter_phase_ += line_flow * dt * metered_pulses_per_l(line_flow);
  if (params_.flow_meter.pulse_jitter > 0.0 || params_.flow_meter.low_flow_error > 0.0) {
    std::uniform_real_distribution<double> jitter(-params_.flow_meter.pulse_jitter,
                                                  params_.flow_meter.pulse_jitter);
    while (meter_phase_ >= next_pulse_at_) {
      ++flow_pulses_;
      next_pulse_at_ = static_cast<double>(flow_pulses_) + 1.0 + jitter(realism_rng_);
    }
  } else {
    // From the accumulated phase, not volume x today's K: a meter that drifts (set_meter_drift)
    // changes the pulses to come, not the ones already counted (a 10 % drift would otherwise
    // put 10 % of all the volume so far into one window).
    flow_pulses_ = static_cast<std::uint64_t>(meter_phase_);
  }
  tank_level_l_ = std::max(0.0, tank_level_l_ - nozzle_flow * dt);

  distance_m_ += speed_m_per_s_ * dt;
  wheel_distance_m_ += speed_m_per_s_ * (1.0 + wheel_slip_) * dt;
  const double true_pulses_per_m =
      params_.wheel.nominal_pulses_per_m / (1.0 + params_.wheel.circumference_error);
  wheel_pulses_ = static_cast<std::uint64_t>(wheel_distance_m_ * true_pulses_per_m);

  const double tau = params_.pressure_sensor.time_constant_s;
  sensor_pressure_mpa_ +=
      (pressure_mpa_ - sensor_pressure_mpa_) * (tau > 0 ? 1.0 - std::exp(-dt / tau) : 1.0);
  time_s_ = t0 + dt;
}

double HydraulicPlant::total_nozzle_flow_l_per_min() const {
  double q = 0.0;
  for (int i = 0; i < params_.nozzle_count; ++i) q += nozzle_flow_l_per_min(i);
  return q;
}

double HydraulicPlant::nozzle_flow_l_per_min(int i) const {
  return valves_.at(static_cast<std::size_t>(i)).flow_l_per_s * 60.0;
}

void HydraulicPlant::record_valve_crossings(bool on) {
  record_crossings_ = on;
  crossings_.clear();
}

std::vector<ValveCrossing> HydraulicPlant::take_valve_crossings() {
  std::vector<ValveCrossing> taken;
  taken.swap(crossings_);
  return taken;
}

double HydraulicPlant::valve_opening(int i) const {
  return valves_.at(static_cast<std::size_t>(i)).position;
}

double HydraulicPlant::nozzle_delivered_l(int i) const {
  return valves_.at(static_cast<std::size_t>(i)).delivered_l;
}

double HydraulicPlant::total_delivered_l() const {
  double v = 0.0;
  for (int i = 0; i < params_.nozzle_count; ++i) v += nozzle_delivered_l(i);
  return v;
}

const NozzleTruth& HydraulicPlant::nozzle_truth(int i) const {
  if (i < 0 || i >= params_.nozzle_count)
    throw std::out_of_range("HydraulicPlant: nozzle index " + std::to_string(i));
  return truth_[static_cast<std::size_t>(i)];
}

double HydraulicPlant::nozzle_full_open_flow_l_per_min(int i, double pressure_mpa) const {
  const NozzleTruth& t = nozzle_truth(i);
  const double kn = t.k_l_per_min_sqrt_mpa;
  const double kv = t.valve_k_l_per_min_sqrt_mpa;
  const double k = kv > 0.0 ? kn * kv / std::sqrt(kn * kn + kv * kv) : kn;
  return orifice_flow_l_per_s(k, pressure_mpa) * 60.0;
}

double HydraulicPlant::nozzle_open_flow_now_l_per_min(int i, double pressure_mpa) const {
  (void)nozzle_truth(i);  // the index check
  return orifice_flow_l_per_s(series_k(i), pressure_mpa) * 60.0;
}

double HydraulicPlant::sensor_current_ma() const {
  if (wire_broken_) return 0.0;
  if (shorted_) return 24.0;
  const auto& s = params_.pressure_sensor;
  // Its own offset (drifting) and span error, then the saturation a little beyond the span
  // (NAMUR NE43: 3.8-20.5 mA).
  const double offset = s.offset_fraction + s.drift_per_hour * time_s_ / 3600.0;
  const double reading = (1.0 + s.span_error) * sensor_pressure_mpa_ / s.full_scale_mpa;
  return std::clamp(4.0 + 16.0 * (offset + reading), 3.8, 20.5);
}

double HydraulicPlant::pressure_sensor_volts() const {
  const double v = sensor_current_ma() * 1e-3 * params_.pressure_sensor.shunt_ohms;
  if (wire_broken_) return 0.0;
  return std::max(0.0, v + sensor_noise_volts_);
}

double HydraulicPlant::true_meter_pulses_per_l() const {
  return params_.flow_meter.nominal_pulses_per_l * (1.0 + params_.flow_meter.k_factor_error) *
         (1.0 + meter_drift_);
}

void HydraulicPlant::set_valve_stuck_open(int i, bool stuck) {
  (void)nozzle_truth(i);  // range check
  valves_[static_cast<std::size_t>(i)].stuck_open = stuck;
  set_valves(valve_mask_);  // moves now, as a command would
}

void HydraulicPlant::set_nozzle_blockage(int i, double fraction) {
  (void)nozzle_truth(i);  // range check
  valves_[static_cast<std::size_t>(i)].blockage = std::clamp(fraction, 0.0, 1.0);
}

void HydraulicPlant::set_filter_blockage(double fraction) {
  filter_blockage_ = std::clamp(fraction, 0.0, 1.0);
}

void HydraulicPlant::set_sensor_wire_broken(bool broken) {
  wire_broken_ = broken;
}
void HydraulicPlant::set_sensor_shorted(bool shorted) {
  shorted_ = shorted;
}

void HydraulicPlant::set_tank_level_l(double litres) {
  tank_level_l_ = std::clamp(litres, 0.0, params_.tank.capacity_l);
}

void HydraulicPlant::set_nozzle_wear(int i, double fraction) {
  (void)nozzle_truth(i);
  valves_[static_cast<std::size_t>(i)].wear = std::clamp(fraction, -0.5, 1.0);
}

void HydraulicPlant::set_valve_ageing(int i, double factor) {
  (void)nozzle_truth(i);
  valves_[static_cast<std::size_t>(i)].ageing = std::clamp(factor, 0.5, 5.0);
}

void HydraulicPlant::set_meter_drift(double fraction) {
  meter_drift_ = std::clamp(fraction, -0.2, 0.2);
}

void HydraulicPlant::set_supply_volts(double volts) {
  supply_volts_ = std::max(0.0, volts);
}

void HydraulicPlant::set_wheel_slip(double slip) {
  wheel_slip_ = std::clamp(slip, -0.49, 0.49);
}

}  // namespace weedspray::sim::plant
