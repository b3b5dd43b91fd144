// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/operation.hpp"

#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

namespace weedspray::daemon {

void Operation::load_calibrations(std::function<double()> delivered_litres) {
  calibrations_.emplace(config_, config_.daemon.state_dir, std::move(delivered_litres));
}

void Operation::attach(Sprayer& sprayer, Nanos start_time, std::function<void()> published) {
  sprayer_ = &sprayer;
  start_time_ = start_time;
  published_ = std::move(published);
}

CalibrationContext Operation::calibration_context() const {
  CalibrationContext c;
  c.idle = state_.state() == SprayerState::kIdle;
  c.have_meter = backends_.flow != nullptr;
  // The pulse count with the control loop's own time of it: under load the main loop's tick
  // comes late, and its clock would stretch or shrink a counted window.
  const ControlStatus control = sprayer_ != nullptr ? sprayer_->control() : ControlStatus{};
  c.now_s = std::chrono::duration<double>(
                (control.cycles > 0 ? control.time : backends_.clock->now()) - start_time_)
                .count();
  c.pulses = control.flow_pulses;
  c.setpoint_mpa = setpoint_mpa_;
  c.pressure_mpa = sprayer_ != nullptr ? sprayer_->pressure().pressure_mpa : 0.0;
  return c;
}

void Operation::reload_config() {
  if (calibrations_) calibrations_->set_config(config_);
  setpoint_mpa_ = config_.pressure.setpoint_mpa;
  decision_threshold_ = config_.spray.decision_threshold;
  nominal_flow_l_per_min_ = config_.spray.nominal_flow_l_per_min;
}

Transition Operation::transition(StateEvent event, const char* cause) {
  const Transition t = state_.handle(event);
  if (t.accepted && t.from != t.to) {
    spdlog::info("state {} -> {} ({})", to_string(t.from), to_string(t.to), cause);
    // A calibration runs only in Idle: ended here, so the parameters published below close
    // its valves and stop the pump in this tick, not the next.
    if (t.to != SprayerState::kIdle && calibrating()) calibrations_->cancel(cause);
    publish_params();
    const std::string status = "STATUS=" + std::string(to_string(t.to));
    sd_notify(0, status.c_str());
  }
  return t;
}

CommandResult Operation::request(StateEvent event, const char* what) {
  const Transition t = transition(event, what);
  if (!t.accepted) return {kErrorNotPermitted, std::string(what) + " refused: " + t.reason};
  return {};
}

CommandResult Operation::start() {
  if (calibrating())
    return {kErrorNotPermitted, "Start refused: a calibration runs (Stop cancels it)"};
  // The bus name appears before the loops have run a cycle: a Start then is kept, not refused.
  if (state_.state() == SprayerState::kStarting) {
    start_when_ready_ = true;
    spdlog::info("Start accepted: spraying as soon as the loops run");
    return {};
  }
  return request(StateEvent::kStart, "Start");
}

CommandResult Operation::stop() {
  if (calibrations_ && calibrations_->cancel("Stop")) {
    publish_params();
    return {};
  }
  if (state_.state() == SprayerState::kStarting && start_when_ready_) {
    start_when_ready_ = false;
    return {};
  }
  return request(StateEvent::kStop, "Stop");
}

void Operation::finish_starting(const PressureStatus& pressure, const ControlStatus& control,
                                bool previous_run_unfinished) {
  if (state_.state() == SprayerState::kStarting && pressure.cycles > 0 && control.cycles > 0) {
    transition(StateEvent::kSetupDone, "loops running");
    sd_notify(0, "READY=1");
    if (config_.daemon.autostart && previous_run_unfinished)
      spdlog::warn("daemon.autostart skipped after an unfinished run: send Start");
    else if (config_.daemon.autostart)
      transition(StateEvent::kStart, "daemon.autostart");
    if (start_when_ready_) transition(StateEvent::kStart, "Start while starting up");
    start_when_ready_ = false;
  }
}

void Operation::follow_key() {
  if (backends_.key == nullptr) return;
  const io::DigitalInputSample key = backends_.key->sample();
  if (key.change_count == key_changes_) return;
  key_changes_ = key.change_count;
  if (key.active) transition(StateEvent::kKeyPressed, "start/stop key");
}

void Operation::update_calibration() {
  if (calibrations_ && calibrations_->update(calibration_context())) publish_params();
}

void Operation::publish_params() {
  LiveParams params = live_params_from(config_);
  params.setpoint_mpa = setpoint_mpa_;
  params.law.decision_threshold = decision_threshold_;
  params.law.nominal_flow_l_per_min = nominal_flow_l_per_min_;
  // A calibration (in Idle) runs the pump for its own valves.
  params.pump_enabled = state_.pump_enabled(calibrating());
  params.valves_enabled = state_.valves_enabled();
  params.trip_reset = trip_reset_;
  if (calibrations_) calibrations_->apply(params);
  sprayer_->set_params(params);
  if (published_) published_();
}

}  // namespace weedspray::daemon
