#include "control/plant/hydraulic_plant.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace weedspray::control::plant {
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
  const double end_of_move = from + dir * rate * moving;
  const double hold = dt - lead - moving;
  const double integral = from * lead + 0.5 * (from + end_of_move) * moving + end_of_move * hold;
  return {integral / dt, end_of_move};
}

}  // namespace

HydraulicPlant::HydraulicPlant(const PlantParams& params, std::uint64_t seed)
    : params_(params), rng_(seed) {
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
  tank_level_l_ = params_.tank.initial_level_l;
}

void HydraulicPlant::set_pump(bool on) {
  pump_on_ = on;
}

void HydraulicPlant::set_return_valve_volts(double volts) {
  return_volts_ = std::clamp(volts, 0.0, params_.return_valve.full_scale_volts);
}

void HydraulicPlant::set_valves(std::uint32_t mask) {
  for (int i = 0; i < params_.nozzle_count; ++i) {
    Valve& v = valves_[static_cast<std::size_t>(i)];
    const bool cmd = ((mask >> i) & 1U) != 0;
    if (cmd == v.commanded) continue;
    v.commanded = cmd;
    const NozzleTruth& t = truth_[static_cast<std::size_t>(i)];
    // Only a spool already travelling coasts on; a motion whose dead time had not ended is
    // cancelled (the coil never pulled in / dropped out).
    const bool travelling = v.motion_start_s <= time_s_ && v.position != v.motion_target;
    v.coast_target = travelling ? v.motion_target : v.position;
    v.motion_target = cmd ? 1.0 : 0.0;
    v.motion_start_s = time_s_ + (cmd ? t.open_delay_s : t.close_delay_s);
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
  auto rate_toward = [&](double target) {
    return target > v.position ? 1.0 / params_.nozzle.open_travel_s
                               : 1.0 / params_.nozzle.close_travel_s;
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

  // Pump: motor speed lags the relay; flow falls linearly with pressure to shut-off; a
  // blocked filter or an almost empty tank starves it.
  const double speed_target = pump_on_ ? 1.0 : 0.0;
  pump_speed_ +=
      (speed_target - pump_speed_) * (1.0 - std::exp(-dt / params_.pump.spin_time_constant_s));
  const double curve = std::max(0.0, 1.0 - p / params_.pump.shutoff_pressure_mpa);
  const double suction = std::clamp(tank_level_l_ / params_.tank.suction_loss_below_l, 0.0, 1.0);
  pump_flow_l_per_s_ = pump_speed_ * params_.pump.open_flow_l_per_min / 60.0 * curve *
                       (1.0 - filter_blockage_) * suction;

  // Return valve: first-order lag toward the commanded opening.
  const auto& rv = params_.return_valve;
  const double open_cmd = std::clamp(
      (return_volts_ - rv.dead_band_volts) / (rv.full_scale_volts - rv.dead_band_volts), 0.0, 1.0);
  return_opening_ += (open_cmd - return_opening_) * (1.0 - std::exp(-dt / rv.time_constant_s));
  return_flow_l_per_s_ = orifice_flow_l_per_s(rv.k_l_per_min_sqrt_mpa * return_opening_, p);

  // Nozzles: mean spool opening over the sub-step (exact for the piecewise-linear motion).
  double nozzle_flow = 0.0;
  for (int i = 0; i < params_.nozzle_count; ++i) {
    Valve& v = valves_[static_cast<std::size_t>(i)];
    const double opening = advance_valve(v, t0, dt);
    const double k = truth_[static_cast<std::size_t>(i)].k_l_per_min_sqrt_mpa * (1.0 - v.blockage);
    v.flow_l_per_s = orifice_flow_l_per_s(k * opening, p);
    v.delivered_l += v.flow_l_per_s * dt;
    nozzle_flow += v.flow_l_per_s;
  }

  // Line pressure: volume balance on the line's compliance.
  const double dp =
      (pump_flow_l_per_s_ - return_flow_l_per_s_ - nozzle_flow) * dt / line_compliance_l_per_mpa(p);
  pressure_mpa_ = std::max(0.0, p + dp);

  // The flow meter sits in the spray line: it sees the nozzles' total flow.
  metered_l_ += nozzle_flow * dt;
  flow_pulses_ = static_cast<std::uint64_t>(metered_l_ * true_meter_pulses_per_l());
  tank_level_l_ = std::max(0.0, tank_level_l_ - nozzle_flow * dt);

  distance_m_ += speed_m_per_s_ * dt;
  const double true_pulses_per_m =
      params_.wheel.nominal_pulses_per_m / (1.0 + params_.wheel.circumference_error);
  wheel_pulses_ = static_cast<std::uint64_t>(distance_m_ * true_pulses_per_m);

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
  return orifice_flow_l_per_s(nozzle_truth(i).k_l_per_min_sqrt_mpa, pressure_mpa) * 60.0;
}

double HydraulicPlant::sensor_current_ma() const {
  if (wire_broken_) return 0.0;
  if (shorted_) return 24.0;
  const auto& s = params_.pressure_sensor;
  // Transmitters saturate a little beyond their span (NAMUR NE43: 3.8-20.5 mA).
  return std::clamp(4.0 + 16.0 * sensor_pressure_mpa_ / s.full_scale_mpa, 3.8, 20.5);
}

double HydraulicPlant::pressure_sensor_volts() const {
  const double v = sensor_current_ma() * 1e-3 * params_.pressure_sensor.shunt_ohms;
  if (wire_broken_) return 0.0;
  return std::max(0.0, v + sensor_noise_volts_);
}

double HydraulicPlant::true_meter_pulses_per_l() const {
  return params_.flow_meter.nominal_pulses_per_l * (1.0 + params_.flow_meter.k_factor_error);
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

}  // namespace weedspray::control::plant
