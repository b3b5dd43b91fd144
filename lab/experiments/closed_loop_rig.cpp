// SPDX-License-Identifier: Apache-2.0
#include "lab/experiments/closed_loop_rig.hpp"
#include "lab/experiments/vocabulary.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "daemon/sprayer/step_settings.hpp"
#include "io/signal_conversion.hpp"

namespace weedspray::lab::experiments {
namespace {

// The daemon's configuration with the rig's boom and valve timing.
daemon::Config daemon_config(const RigConfig& c) {
  daemon::Config config = daemon::default_settings();
  config.boom.nozzles = c.plant.nozzle_count;
  config.pwm.frequency_hz = c.pwm_frequency_hz;
  config.pwm.staggered = c.fixes.staggered;
  config.pwm.min_on_s = c.pwm_min_on_s;
  config.pwm.min_off_s = c.pwm_min_off_s;
  return config;
}

// The daemon's valve schedule (order, immediate start/stop) for the rig's boom and timing.
PwmConfig pwm_config(const RigConfig& c) {
  return daemon::pwm_config(daemon_config(c));
}

PressureLoopConfig pressure_loop_config(const RigConfig& c) {
  PressureLoopConfig p;
  p.mode = c.controller_mode;
  p.controller = c.controller;
  p.period_s = c.control_period_s;
  return p;
}

// The daemon's duty step for the rig's boom, with the rig's trim and filter settings.
NozzleCommandConfig nozzle_command_config(const RigConfig& c) {
  NozzleCommandConfig command = daemon::nozzle_command_config(daemon_config(c));
  command.cycle_s = c.command_period_s;
  if (!c.alternate_periods) command.pwm_period_s = 0.0;
  if (!c.quantise) command.quantiser_level_count = 0;
  command.trim.trim = c.flow_trim;
  command.trim.window_s = c.flow_trim_window_s;
  command.trim.pressure_filter_s = c.compensation_filter_s;
  command.compensation_filter_s = c.compensation_filter_s;
  return command;
}

// Without the law's clamp the duty is the line's, limited to 0..100 %.
SprayLawConfig command_law(const RigConfig& c) {
  if (c.duty_clamp) return *c.duty_clamp;
  SprayLawConfig open;
  open.min_duty_pct = 0.0;
  open.max_duty_pct = 100.0;
  open.low_duty_policy = LowDutyPolicy::kClose;
  return open;
}

std::chrono::nanoseconds nanos(double s) {
  return std::chrono::nanoseconds(std::llround(s * 1e9));
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

const PressureLoopConfig& daemon_pressure_loop_config() {
  static const PressureLoopConfig config = daemon::pressure_loop_config(daemon::default_settings());
  return config;
}
double daemon_pwm_min_on_s() {
  return daemon::default_settings().pwm.min_on_s;
}
double daemon_pwm_min_off_s() {
  return daemon::default_settings().pwm.min_off_s;
}
double daemon_over_pressure_mpa() {
  return daemon::default_settings().alarms.over_pressure_mpa;
}
double daemon_control_loop_period_s() {
  return std::chrono::duration<double>(daemon::kControlLoopPeriod).count();
}

ClosedLoopRig::ClosedLoopRig(const RigConfig& config)
    : config_(config),
      plant_(config.plant, config.seed),
      pressure_step_(pressure_loop_config(config)),
      pwm_(pwm_config(config)),
      command_step_(nozzle_command_config(config)),
      boom_trim_pressure_(config.compensation_filter_s) {
  if (!(config.control_period_s > 0.0 && config.control_period_s <= 0.1))
    throw std::invalid_argument("RigConfig.control_period_s must be in (0, 0.1]");
  if (!(config.command_period_s > 0.0 && config.command_period_s <= 0.1))
    throw std::invalid_argument("RigConfig.command_period_s must be in (0, 0.1]");
  if (config.adc_bits < 8 || config.adc_bits > 24)
    throw std::invalid_argument("RigConfig.adc_bits must be in [8, 24]");
  for (const double delay : {config.converter_lead_s, config.converter_lag_s}) {
    if (!(delay >= 0.0 && delay < config.control_period_s))
      throw std::invalid_argument(
          "RigConfig.converter_lead_s and converter_lag_s must be in [0, control_period_s)");
  }
  if (!(config.meter_pulses_per_l > 0.0))
    throw std::invalid_argument("RigConfig.meter_pulses_per_l must be > 0");
  if (config.duty_clamp) validate(*config.duty_clamp);
  for (auto& line : lines_) line = NozzleLine{};
  if (config.nozzle_health) {
    NozzleHealthConfig h = *config.nozzle_health;
    h.nozzles = static_cast<std::size_t>(config.plant.nozzle_count);
    health_.emplace(h);
  }
  if (config.identify_nozzles) fit_.emplace(static_cast<std::size_t>(config.plant.nozzle_count));
  // One staggered phase, as the daemon cuts it.
  phase_window_s_ = 1.0 / (config.pwm_frequency_hz * config.plant.nozzle_count);
  if (health_) health_windows_.emplace(nanos(phase_window_s_), kMeterLag);
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
  const std::size_t n = std::min(flow_l_per_min.size(), requested_flows_.size());
  std::copy_n(flow_l_per_min.begin(), n, requested_flows_.begin());
  flows_requested_ = true;
  // Once running, the next control tick takes them (as the daemon's next cycle does); until
  // then the latched duties and their promise hold (a request every tick, as a speed-following
  // target makes, leaves the model trim no tick without a promise).
  if (!started_) apply_flow_requests(0.0);
}

void ClosedLoopRig::command_duties(std::span<const double> duty_pct) {
  flows_requested_ = false;
  duties_.fill(0.0);
  const std::size_t n = std::min(duty_pct.size(), static_cast<std::size_t>(plant_.nozzle_count()));
  for (std::size_t i = 0; i < n; ++i) duties_[i] = std::clamp(duty_pct[i], 0.0, 100.0);
  set_pwm_duties();
}

void ClosedLoopRig::set_pwm_duties() {
  const std::span<const double> duties(duties_.data(),
                                       static_cast<std::size_t>(plant_.nozzle_count()));
  // Before start() the schedule is not running: the duties are latched at its start.
  if (started_) {
    pwm_.set_duties(duties, nanos(plant_.time_s() - pwm_start_s_));
  } else {
    pwm_.set_duties(duties);
  }
}

void ClosedLoopRig::apply_flow_requests(double dt_s) {
  const auto n = static_cast<std::size_t>(plant_.nozzle_count());
  // The model trim judges each request at the pressure the last duties were compensated with.
  const double last_pressure = command_step_.outputs().compensation_pressure_mpa;
  std::array<NozzleLine, plant::kMaxNozzles> lines{};
  std::array<double, plant::kMaxNozzles> flows{};
  for (std::size_t k = 0; k < n; ++k) {
    // The spray-rate law owns the full-open rule (spray_rate_law.hpp); the rig only hands it
    // the calibrated full-open flow.
    lines[k] = lines_[k];
    if (full_open_flows_[k] > 0.0) lines[k].full_open_flow_l_per_min = full_open_flows_[k];
    // The model trim asks the line for what makes this nozzle deliver the request, but never
    // below a full opening the law chose (boom_trim.hpp).
    double flow = requested_flows_[k];
    line_slopes_[k] = line_slope_l_per_min_per_pct(lines[k], last_pressure);
    if (boom_trim_ && flow > 0.0 && raw_duty_for_flow_pct(lines[k], flow, last_pressure) < 100.0)
      flow = boom_trim_->flow_to_ask(flow, line_slopes_[k]);
    flows[k] = flow;
  }
  // The daemon's step: the law's duties, then (a control tick, the trim on) the flow trim,
  // which decides itself whether a window is usable (pressure off set-point, too little flow).
  NozzleCommandInputs in = command_inputs(dt_s, true);
  in.target_flow_l_per_min = std::span<const double>(flows.data(), n);
  in.lines = std::span<const NozzleLine>(lines.data(), n);
  in.schedule_time_s = started_ ? plant_.time_s() - pwm_start_s_ : -1.0;
  const NozzleCommandOutputs& out = command_step_.step(in);
  const double pressure = out.compensation_pressure_mpa;
  for (std::size_t k = 0; k < n; ++k) {
    duties_[k] = out.duty_pct[k];
    // What the law promises for the duty it chose (the model trim's reference): a clamp that
    // raised or lowered the duty changed the promise too.
    promised_flows_[k] = promised_flow_l_per_min(lines[k], out.law_duty_pct[k], pressure);
    commanded_promise_[k] = promised_flow_l_per_min(lines[k], duties_[k], pressure);
  }
  set_pwm_duties();
}

void ClosedLoopRig::step_not_spraying(double dt_s) {
  // The daemon keeps stepping its duties while a calibration or a re-check holds the valves,
  // told not to spray: the trim drops its part-filled meter window then, so the litres of the
  // held valves never enter a window the next request's promise is judged against.
  const auto n = static_cast<std::size_t>(plant_.nozzle_count());
  const std::array<double, plant::kMaxNozzles> no_flows{};
  NozzleCommandInputs in = command_inputs(dt_s, false);
  in.target_flow_l_per_min = std::span<const double>(no_flows.data(), n);
  in.lines = std::span<const NozzleLine>(lines_.data(), n);
  command_step_.step(in);
}

NozzleCommandInputs ClosedLoopRig::command_inputs(double dt_s, bool spraying) const {
  NozzleCommandInputs in;
  in.dt_s = dt_s;
  in.spraying = spraying;
  in.trim = config_.fixes.flow_feedback && !boom_trim_ && dt_s > 0.0;
  in.law = command_law(config_);
  in.pressure_compensation = config_.fixes.pressure_compensation;
  in.pressure_mpa = measured_pressure_mpa_;
  in.setpoint_mpa = config_.setpoint_mpa;
  in.pulses = plant_.flow_meter_pulses();
  in.pulses_per_litre = config_.meter_pulses_per_l;
  return in;
}

void ClosedLoopRig::start() {
  if (started_) return;
  plant_.set_pump(true);
  const double now = plant_.time_s();
  measured_pressure_mpa_ = read_pressure_mpa();
  boom_trim_pressure_.reset();
  boom_trim_pressure_.update(measured_pressure_mpa_, 0.0);
  pwm_start_s_ = now;
  pwm_.start(std::chrono::nanoseconds(0));
  started_ = true;
  pending_edge_ = pwm_.next_edge();
  last_edge_s_ = now;
  next_control_s_ = now;
  next_command_s_ = now;
  sampled_pressure_mpa_ = measured_pressure_mpa_;
  next_sample_s_ = now + config_.control_period_s - config_.converter_lead_s;
  dac_due_s_ = -1.0;
  next_record_s_ = now;
  boom_trim_windows_.reset();
  if (health_windows_) health_windows_->restart();
  if (fit_) {
    next_fit_window_s_ = now + phase_window_s_;
    window_promised_l_.fill(0.0);
  }
}

void ClosedLoopRig::fit_window_closed() {
  const std::uint64_t pulses = plant_.flow_meter_pulses();
  fit_->add_window(std::span<const double>(window_promised_l_.data(),
                                           static_cast<std::size_t>(plant_.nozzle_count())),
                   static_cast<double>(pulses - fit_pulses_) / config_.meter_pulses_per_l);
  fit_pulses_ = pulses;
  window_promised_l_.fill(0.0);
  next_fit_window_s_ += phase_window_s_;
}

void ClosedLoopRig::update_health_windows() {
  const double now = plant_.time_s();
  if (!health_windows_->update(std::chrono::nanoseconds(0), applied_mask_,
                               nanos(last_edge_s_ - pwm_start_s_), nanos(now - pwm_start_s_),
                               plant_.flow_meter_pulses(), config_.meter_pulses_per_l))
    return;
  const auto nozzles = static_cast<std::size_t>(plant_.nozzle_count());
  health_->add_window(health_windows_->open_s().first(nozzles), health_windows_->metered_l(),
                      health_windows_->window_s());
  for (std::size_t i = 0; i < nozzles; ++i)
    health_max_evidence_ = std::max(health_max_evidence_, health_->evidence(i));
}

void ClosedLoopRig::account_open_time(double step_s) {
  const double t0 = plant_.time_s();
  const double t1 = t0 + step_s;
  for (int i = 0; i < plant_.nozzle_count(); ++i) {
    const auto k = static_cast<std::size_t>(i);
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
  // The pressure step holds the valves closed while its reading is no pressure or it tripped.
  if (pressure_step_.outputs().hold_valves) mask = 0;
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
  if (mask != applied_mask_) last_edge_s_ = now;
  plant_.set_valves(mask);
  applied_mask_ = mask;
}

void ClosedLoopRig::restart_identification() {
  if (fit_) fit_->reset();
  fit_promised_l_.fill(0.0);
  window_promised_l_.fill(0.0);
  fit_pulses_ = plant_.flow_meter_pulses();
}

ClosedLoopRig::PressureReading ClosedLoopRig::read_pressure() const {
  // ADC quantisation, then the label conversion volts -> mA -> MPa with the daemon's fault rule.
  const double full = static_cast<double>((1L << config_.adc_bits) - 1);
  const double counts = std::round(
      std::clamp(plant_.pressure_sensor_volts() / config_.adc_reference_volts, 0.0, 1.0) * full);
  io::CurrentLoopSensorConfig sensor;
  sensor.shunt_ohms = config_.sensor_shunt_ohms;
  sensor.pressure_at_max_mpa = config_.sensor_full_scale_mpa;
  const io::PressureReading reading =
      io::pressure_from_sensor_volts(counts / full * config_.adc_reference_volts, sensor);
  return {reading.pressure_mpa, reading.ok()};
}

double ClosedLoopRig::read_pressure_mpa() {
  const PressureReading reading = read_pressure();
  sensor_ok_ = reading.ok;
  return reading.pressure_mpa;
}

double ClosedLoopRig::next_edge_time_s() const {
  return pwm_start_s_ + seconds(pending_edge_.time);
}

void ClosedLoopRig::control_tick() {
  const double dt = config_.control_period_s;
  measured_pressure_mpa_ =
      config_.converter_lead_s > 0.0 ? sampled_pressure_mpa_ : read_pressure_mpa();
  boom_trim_pressure_.update(measured_pressure_mpa_, dt);
  PressureLoopInputs in;
  in.pressure_mpa = measured_pressure_mpa_;
  in.sensor_ok = sensor_ok_;
  in.setpoint_mpa = config_.setpoint_mpa;
  in.over_pressure_mpa = config_.over_pressure_mpa;
  in.pump_enabled = true;
  const PressureLoopOutputs& out = pressure_step_.step(in);
  plant_.set_pump(out.run);
  const double volts = 10.0 * (1.0 - out.closure);
  if (config_.converter_lag_s > 0.0) {
    dac_pending_volts_ = volts;
    dac_due_s_ = plant_.time_s() + config_.converter_lag_s;
  } else {
    plant_.set_return_valve_volts(volts);
  }
  if (out.hold_valves && applied_mask_ != 0) valve_edge(0);
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
    const double pressure_error =
        std::abs(boom_trim_pressure_.value() - config_.setpoint_mpa) / config_.setpoint_mpa;
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
    double next = std::min({end, edge_t, next_control_s_, next_command_s_});
    if (config_.record_period_s > 0.0) next = std::min(next, next_record_s_);
    if (config_.converter_lead_s > 0.0) next = std::min(next, next_sample_s_);
    if (dac_due_s_ >= 0.0) next = std::min(next, dac_due_s_);
    if (fit_) next = std::min(next, next_fit_window_s_);
    if (health_windows_ && health_windows_->meter_due().count() >= 0)
      next = std::min(next, pwm_start_s_ + seconds(health_windows_->meter_due()));
    if (next > plant_.time_s()) {
      const double step_s = next - plant_.time_s();
      if (fit_) account_open_time(step_s);
      plant_.step(step_s);
    }
    const double now = plant_.time_s();
    constexpr double kEps = 1e-9;
    if (fit_ && next_fit_window_s_ <= now + kEps) fit_window_closed();
    // The windows see the mask that held until now, then the edges of this instant.
    if (health_windows_) update_health_windows();
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
    // The control loop's tick: the duties for the latest reading (the daemon's control loop
    // reads the pressure loop's last published sample).
    if (next_command_s_ <= now + kEps) {
      if (flows_requested_) {
        apply_flow_requests(config_.command_period_s);
      } else {
        step_not_spraying(config_.command_period_s);
      }
      next_command_s_ += config_.command_period_s;
    }
    if (config_.record_period_s > 0.0 && next_record_s_ <= now + kEps) {
      trace_.push_back({now, plant_.line_pressure_mpa(), plant_.boom_pressure_mpa(),
                        measured_pressure_mpa_, plant_.total_nozzle_flow_l_per_min(),
                        10.0 * (1.0 - pressure_step_.outputs().closure), applied_mask_});
      next_record_s_ += config_.record_period_s;
    }
    if (now >= end - kEps) break;
  }
}

}  // namespace weedspray::lab::experiments
