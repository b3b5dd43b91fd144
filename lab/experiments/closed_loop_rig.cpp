#include "lab/experiments/closed_loop_rig.hpp"
#include "lab/experiments/vocabulary.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace weedspray::lab::experiments {
namespace {

PwmConfig pwm_config(const RigConfig& c) {
  PwmConfig p;
  p.valve_count = static_cast<std::size_t>(c.plant.nozzle_count);
  p.frequency_hz = c.pwm_frequency_hz;
  p.phase_mode = c.fixes.staggered ? PwmPhaseMode::kStaggered : PwmPhaseMode::kSynchronous;
  return p;
}

// The valve's datasheet timing the phase-window fit assumes (not the machine's drawn truth),
// and how much longer a pulse flows than it is commanded by it [s].
const plant::NozzleParams kValveLabel{};
const double kFlowLagStretchS = (kValveLabel.close_delay_s + kValveLabel.close_travel_s / 2.0) -
                                (kValveLabel.open_delay_s + kValveLabel.open_travel_s / 2.0);

double seconds(std::chrono::nanoseconds t) {
  return static_cast<double>(t.count()) * 1e-9;
}

}  // namespace

FuzzyPidConfig default_fuzzy_pid_config() {
  FuzzyPidConfig c;
  // Found by tune_step_controllers() (seed 1, 0.2 MPa, 4 nozzles open; 820 candidates).
  c.base.gains = {44.0, 360.4, 0.2253};
  c.base.output_min = 0.0;
  c.base.output_max = 1.0;
  c.base.anti_windup = AntiWindup::kBackCalculation;
  c.base.derivative_filter_s = 0.01;
  c.correction_weights = {4.4, 72.09, 0.02253};
  c.error_range = 0.2;
  return c;
}

// Found by tune_step_controllers() (same search, ITAE-optimal on the same plant).
PidGains default_conventional_pid_gains() {
  return {35.2, 225.3, 0.1408};
}

ClosedLoopRig::ClosedLoopRig(const RigConfig& config)
    : config_(config),
      plant_(config.plant, config.seed),
      controller_(config.controller_mode, config.controller),
      pwm_(pwm_config(config)),
      trim_(config.flow_trim),
      trim_windows_(config.flow_trim_window_s) {
  if (!(config.control_period_s > 0.0 && config.control_period_s <= 0.1))
    throw std::invalid_argument("RigConfig.control_period_s must be in (0, 0.1]");
  if (config.adc_bits < 8 || config.adc_bits > 24)
    throw std::invalid_argument("RigConfig.adc_bits must be in [8, 24]");
  for (const double delay : {config.converter_lead_s, config.converter_lag_s}) {
    if (!(delay >= 0.0 && delay < config.control_period_s))
      throw std::invalid_argument(
          "RigConfig.converter_lead_s and converter_lag_s must be in [0, control_period_s)");
  }
  if (!(config.meter_pulses_per_l > 0.0))
    throw std::invalid_argument("RigConfig.meter_pulses_per_l must be > 0");
  if (!(config.flow_trim_window_s > 0.0))
    throw std::invalid_argument("RigConfig.flow_trim_window_s must be > 0");
  if (config.duty_clamp) validate(*config.duty_clamp);
  for (auto& line : lines_) line = NozzleLine{};
  if (config.nozzle_health) {
    NozzleHealthConfig h = *config.nozzle_health;
    h.nozzles = static_cast<std::size_t>(config.plant.nozzle_count);
    health_.emplace(h);
  }
  if (config.identify_nozzles) fit_.emplace(static_cast<std::size_t>(config.plant.nozzle_count));
  phase_windows_ = health_ || fit_;
  if (phase_windows_) {
    health_window_s_ = 1.0 / (config.pwm_frequency_hz * config.plant.nozzle_count);
    if (!(config.health_flow_lag_s >= 0.0 && config.health_flow_lag_s < health_window_s_))
      throw std::invalid_argument("RigConfig.health_flow_lag_s must be in [0, one PWM phase)");
  }
  if (config.fixes.flow_feedback && config.fixes.model_trim) boom_trim_.emplace(config.boom_trim);
  plant_.set_ground_speed(config.ground_speed_m_per_s);
  plant_.set_return_valve_volts(10.0);  // fully open: the safe state, no pressure
}

void ClosedLoopRig::set_nozzle_lines(std::span<const NozzleLine> lines) {
  const std::size_t n = std::min(lines.size(), lines_.size());
  for (std::size_t i = 0; i < n; ++i) {
    validate(lines[i]);
    lines_[i] = lines[i];
  }
}

void ClosedLoopRig::set_full_open_flows(std::span<const double> flow_l_per_min) {
  full_open_flows_.fill(0.0);
  const std::size_t n = std::min(flow_l_per_min.size(), full_open_flows_.size());
  std::copy_n(flow_l_per_min.begin(), n, full_open_flows_.begin());
}

void ClosedLoopRig::request_flows(std::span<const double> flow_l_per_min) {
  requested_flows_.fill(0.0);
  promised_flows_.fill(0.0);
  const std::size_t n = std::min(flow_l_per_min.size(), requested_flows_.size());
  std::copy_n(flow_l_per_min.begin(), n, requested_flows_.begin());
  flows_requested_ = true;
  apply_flow_requests();
}

void ClosedLoopRig::command_duties(std::span<const double> duty_pct) {
  flows_requested_ = false;
  duties_.fill(0.0);
  const std::size_t n = std::min(duty_pct.size(), static_cast<std::size_t>(plant_.nozzle_count()));
  for (std::size_t i = 0; i < n; ++i) duties_[i] = std::clamp(duty_pct[i], 0.0, 100.0);
  pwm_.set_duties(std::span<const double>(duties_.data(), n));
}

void ClosedLoopRig::apply_flow_requests() {
  const int n = plant_.nozzle_count();
  const double pressure = config_.fixes.pressure_compensation ? filtered_pressure_mpa_ : 0.0;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    // The spray-rate law owns the full-open rule (spray_rate_law.hpp); the rig only hands it
    // the calibrated full-open flow.
    NozzleLine line = lines_[k];
    if (full_open_flows_[k] > 0.0) line.full_open_flow_l_per_min = full_open_flows_[k];
    // The model trim asks the line for what makes this nozzle deliver the request, but never
    // below a full opening the law chose (boom_trim.hpp).
    double flow = requested_flows_[k];
    line_slopes_[k] = line_slope_l_per_min_per_pct(line, pressure);
    if (boom_trim_ && flow > 0.0 && raw_duty_for_flow_pct(line, flow, pressure) < 100.0)
      flow = boom_trim_->flow_to_ask(flow, line_slopes_[k]);
    double duty = flow > 0.0 ? raw_duty_for_flow_pct(line, flow, pressure) : 0.0;
    if (config_.duty_clamp) duty = clamp_duty_for_flow_pct(*config_.duty_clamp, duty, flow);
    // What the law promises for the duty it chose (the trim's reference): a clamp that raised
    // or lowered the duty changed the promise too.
    promised_flows_[k] = promised_flow_l_per_min(line, duty, pressure);
    if (config_.fixes.flow_feedback && !boom_trim_)
      duty = trimmed_duty_pct(line, duty, trim_.correction(), pressure);
    duties_[k] = std::clamp(duty, 0.0, 100.0);
    commanded_promise_[k] = promised_flow_l_per_min(line, duties_[k], pressure);
  }
  pwm_.set_duties(std::span<const double>(duties_.data(), static_cast<std::size_t>(n)));
}

void ClosedLoopRig::start() {
  if (started_) return;
  started_ = true;
  plant_.set_pump(true);
  const double now = plant_.time_s();
  measured_pressure_mpa_ = read_pressure_mpa();
  filtered_pressure_mpa_ = measured_pressure_mpa_;
  controller_.enable(0.0, config_.setpoint_mpa, measured_pressure_mpa_);
  pwm_start_s_ = now;
  pwm_.start(std::chrono::nanoseconds(0));
  pending_edge_ = pwm_.next_edge();
  next_control_s_ = now;
  sampled_pressure_mpa_ = measured_pressure_mpa_;
  next_sample_s_ = now + config_.control_period_s - config_.converter_lead_s;
  dac_due_s_ = -1.0;
  next_record_s_ = now;
  boom_trim_windows_.reset();
  trim_windows_.reset();
  if (phase_windows_) {
    next_health_window_s_ = now + health_window_s_;
    next_health_meter_s_ = -1.0;
    health_open_s_.fill(0.0);
    window_promised_l_.fill(0.0);
    health_pulses_ = plant_.flow_meter_pulses();
  }
}

void ClosedLoopRig::health_window_closed() {
  health_pending_open_s_ = health_open_s_;
  health_open_s_.fill(0.0);
  if (fit_) {
    const std::uint64_t pulses = plant_.flow_meter_pulses();
    fit_->add_window(std::span<const double>(window_promised_l_.data(),
                                             static_cast<std::size_t>(plant_.nozzle_count())),
                     static_cast<double>(pulses - fit_pulses_) / config_.meter_pulses_per_l);
    fit_pulses_ = pulses;
    window_promised_l_.fill(0.0);
  }
  const double closed_at_s = next_health_window_s_;
  next_health_window_s_ += health_window_s_;
  if (!health_) return;  // the fit reads the meter at the window's own end (above)
  next_health_meter_s_ = closed_at_s + config_.health_flow_lag_s;
  if (config_.health_flow_lag_s <= 0.0) health_meter_window_closed();
}

void ClosedLoopRig::health_meter_window_closed() {
  const std::uint64_t pulses = plant_.flow_meter_pulses();
  const double litres = static_cast<double>(pulses - health_pulses_) / config_.meter_pulses_per_l;
  health_pulses_ = pulses;
  next_health_meter_s_ = -1.0;
  const auto nozzles = static_cast<std::size_t>(plant_.nozzle_count());
  health_->add_window(std::span<const double>(health_pending_open_s_.data(), nozzles), litres,
                      health_window_s_);
  for (std::size_t i = 0; i < nozzles; ++i)
    health_max_evidence_ = std::max(health_max_evidence_, health_->evidence(i));
}

void ClosedLoopRig::account_open_time(double step_s) {
  const double t0 = plant_.time_s();
  const double t1 = t0 + step_s;
  for (int i = 0; i < plant_.nozzle_count(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    if ((applied_mask_ >> i) & 1U) health_open_s_[k] += step_s;
    if (!fit_) continue;
    fit_promised_l_[k] += step_s * commanded_promise_[k] / 60.0;
    // The fit counts the time the nozzle flows by its valve's label timing (the commanded
    // pulse moved by the mean open and close lags), at the line's flow per flowing second
    // (its promise over the share of the period it flows).
    double flowing_s = 0.0;
    for (const auto& [on, off] : {flow_previous_[k], flow_current_[k]})
      flowing_s += std::max(0.0, std::min(t1, off) - std::max(t0, on));
    const double flowing_share =
        duties_[k] >= 100.0
            ? 1.0
            : std::min(1.0, duties_[k] / 100.0 + kFlowLagStretchS * config_.pwm_frequency_hz);
    if (duties_[k] > 0.0)
      window_promised_l_[k] += flowing_s * commanded_promise_[k] / 60.0 / flowing_share;
  }
}

void ClosedLoopRig::valve_edge(std::uint32_t mask) {
  const double now = plant_.time_s();
  const plant::NozzleParams label = kValveLabel;
  for (int i = 0; i < plant_.nozzle_count(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const bool was = (applied_mask_ >> i) & 1U;
    const bool is = (mask >> i) & 1U;
    if (!was && is) {
      flow_previous_[k] = flow_current_[k];
      flow_current_[k] = {now + label.open_delay_s + label.open_travel_s / 2.0,
                          std::numeric_limits<double>::infinity()};
    } else if (was && !is) {
      flow_current_[k].second = now + label.close_delay_s + label.close_travel_s / 2.0;
    }
  }
  plant_.set_valves(mask);
  applied_mask_ = mask;
}

void ClosedLoopRig::restart_identification() {
  if (fit_) fit_->reset();
  fit_promised_l_.fill(0.0);
  window_promised_l_.fill(0.0);
  fit_pulses_ = plant_.flow_meter_pulses();
}

double ClosedLoopRig::read_pressure_mpa() const {
  // ADC quantisation, then the label conversion volts -> mA -> MPa.
  const double full = static_cast<double>((1L << config_.adc_bits) - 1);
  const double counts = std::round(
      std::clamp(plant_.pressure_sensor_volts() / config_.adc_reference_volts, 0.0, 1.0) * full);
  const double volts = counts / full * config_.adc_reference_volts;
  const double milliamps = volts / config_.sensor_shunt_ohms * 1000.0;
  return (milliamps - 4.0) / 16.0 * config_.sensor_full_scale_mpa;
}

double ClosedLoopRig::next_edge_time_s() const {
  return pwm_start_s_ + seconds(pending_edge_.time);
}

void ClosedLoopRig::control_tick() {
  const double dt = config_.control_period_s;
  measured_pressure_mpa_ =
      config_.converter_lead_s > 0.0 ? sampled_pressure_mpa_ : read_pressure_mpa();
  const double alpha = 1.0 - std::exp(-dt / config_.compensation_filter_s);
  filtered_pressure_mpa_ += alpha * (measured_pressure_mpa_ - filtered_pressure_mpa_);
  const double u = controller_.update(config_.setpoint_mpa, measured_pressure_mpa_, dt);
  if (config_.converter_lag_s > 0.0) {
    dac_pending_volts_ = 10.0 * (1.0 - u);
    dac_due_s_ = plant_.time_s() + config_.converter_lag_s;
  } else {
    plant_.set_return_valve_volts(10.0 * (1.0 - u));
  }

  const double pressure_error =
      std::abs(filtered_pressure_mpa_ - config_.setpoint_mpa) / config_.setpoint_mpa;
  // FlowTrim decides itself whether a window is usable (pressure off set-point, too little
  // flow); the rig only measures, through the daemon's window cutter.
  if (config_.fixes.flow_feedback && !boom_trim_ && flows_requested_) {
    FlowTrimTick tick;
    for (int i = 0; i < plant_.nozzle_count(); ++i) {
      const auto k = static_cast<std::size_t>(i);
      // The trim compares against what the lines promise for the duties actually latched.
      tick.promised_l_per_min += commanded_promise_[k];
      tick.open_fraction += duties_[k] / 100.0 / plant_.nozzle_count();
    }
    tick.pressure_error_fraction = pressure_error;
    tick.pulses = plant_.flow_meter_pulses();
    FlowTrimInput input;
    if (trim_windows_.tick(dt, tick, config_.meter_pulses_per_l, input)) trim_.update(input);
  }
  if (flows_requested_) apply_flow_requests();
  if (boom_trim_) {
    // The model trim (lab only, boom_trim.hpp), fed a tick at a time: the lines' promise at
    // the duties just latched.
    double promised = 0.0;
    double slope = 0.0;
    for (int i = 0; i < plant_.nozzle_count(); ++i) {
      const auto k = static_cast<std::size_t>(i);
      if (duties_[k] > 0.0) promised += promised_flows_[k];
      if (duties_[k] > 0.0 && duties_[k] < 100.0) slope += line_slopes_[k];
    }
    const bool usable =
        flows_requested_ && pressure_error <= config_.flow_trim.max_pressure_error_fraction;
    BoomTrimWindow window;
    if (boom_trim_windows_.tick(dt, promised, slope, usable, plant_.flow_meter_pulses(),
                                config_.meter_pulses_per_l, window))
      boom_trim_->add_window(window);
  }
}

void ClosedLoopRig::run_for(double duration_s) {
  if (!started_) throw std::logic_error("ClosedLoopRig::run_for before start()");
  const double end = plant_.time_s() + duration_s;
  while (true) {
    const double edge_t = next_edge_time_s();
    double next = std::min({end, edge_t, next_control_s_});
    if (config_.record_period_s > 0.0) next = std::min(next, next_record_s_);
    if (config_.converter_lead_s > 0.0) next = std::min(next, next_sample_s_);
    if (dac_due_s_ >= 0.0) next = std::min(next, dac_due_s_);
    if (phase_windows_) {
      next = std::min(next, next_health_window_s_);
      if (next_health_meter_s_ >= 0.0) next = std::min(next, next_health_meter_s_);
    }
    if (next > plant_.time_s()) {
      const double step_s = next - plant_.time_s();
      if (phase_windows_) account_open_time(step_s);
      plant_.step(step_s);
    }
    const double now = plant_.time_s();
    constexpr double kEps = 1e-9;
    if (phase_windows_ && next_health_meter_s_ >= 0.0 && next_health_meter_s_ <= now + kEps)
      health_meter_window_closed();
    if (phase_windows_ && next_health_window_s_ <= now + kEps) health_window_closed();
    while (next_edge_time_s() <= now + kEps) {
      valve_edge(pending_edge_.valve_mask);
      pending_edge_ = pwm_.next_edge();
    }
    if (dac_due_s_ >= 0.0 && dac_due_s_ <= now + kEps) {
      plant_.set_return_valve_volts(dac_pending_volts_);
      dac_due_s_ = -1.0;
    }
    if (config_.converter_lead_s > 0.0 && next_sample_s_ <= now + kEps) {
      sampled_pressure_mpa_ = read_pressure_mpa();
      next_sample_s_ += config_.control_period_s;
    }
    if (next_control_s_ <= now + kEps) {
      control_tick();
      next_control_s_ += config_.control_period_s;
    }
    if (config_.record_period_s > 0.0 && next_record_s_ <= now + kEps) {
      trace_.push_back({now, plant_.line_pressure_mpa(), plant_.boom_pressure_mpa(),
                        measured_pressure_mpa_, plant_.total_nozzle_flow_l_per_min(),
                        10.0 * (1.0 - controller_.output()), applied_mask_});
      next_record_s_ += config_.record_period_s;
    }
    if (now >= end - kEps) break;
  }
}

}  // namespace weedspray::lab::experiments
