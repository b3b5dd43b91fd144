// SPDX-License-Identifier: Apache-2.0
// The sprayer's operating state (main thread): the state machine, the pressure set-point, the
// rate law's decision threshold and nominal flow, the calibrations, and the live parameters they
// make for the loops, published on every change (the status follows at once through `published`).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

#include "daemon/backends/backends.hpp"
#include "daemon/bus/status.hpp"
#include "daemon/config/config.hpp"
#include "daemon/sprayer/calibrations.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "daemon/supervision/state_machine.hpp"

namespace weedspray::daemon {

class Operation {
 public:
  // `config`: the running configuration, kept current by reloads; `backends` give the clock.
  Operation(const Config& config, const Backends& backends)
      : config_(config),
        backends_(backends),
        setpoint_mpa_(config.pressure.setpoint_mpa),
        decision_threshold_(config.spray.decision_threshold),
        nominal_flow_l_per_min_(config.spray.nominal_flow_l_per_min) {}

  // Loads the calibrations; `delivered_litres`: the world's true volume (catch tests), if any.
  void load_calibrations(std::function<double()> delivered_litres);
  // From the loops' start: where the parameters go, and what shows them.
  void attach(Sprayer& sprayer, Nanos start_time, std::function<void()> published);

  SprayerState state() const noexcept { return state_.state(); }
  bool pump_enabled() const noexcept { return state_.pump_enabled(calibrating()); }
  bool calibrating() const noexcept { return calibrations_ && calibrations_->running(); }
  Calibrations* calibrations() noexcept { return calibrations_ ? &*calibrations_ : nullptr; }
  const Calibrations* calibrations() const noexcept {
    return calibrations_ ? &*calibrations_ : nullptr;
  }
  CalibrationContext calibration_context() const;

  double setpoint_mpa() const noexcept { return setpoint_mpa_; }
  void set_setpoint_mpa(double mpa) noexcept { setpoint_mpa_ = mpa; }
  // The rate law's live settings: the density below which a zone is not sprayed, and the
  // nozzle flow at full weed cover and the nominal speed (the dose).
  double decision_threshold() const noexcept { return decision_threshold_; }
  void set_decision_threshold(double threshold) noexcept { decision_threshold_ = threshold; }
  double nominal_flow_l_per_min() const noexcept { return nominal_flow_l_per_min_; }
  void set_nominal_flow_l_per_min(double flow) noexcept { nominal_flow_l_per_min_ = flow; }
  // Bumped by ClearAlarms: the loops and the nozzle health detector restart their trips.
  std::uint64_t trip_reset() const noexcept { return trip_reset_; }
  void reset_trips() noexcept { ++trip_reset_; }
  // The configuration was reloaded: the calibrations' part of it, and the set-point, the
  // threshold and the dose back to the configured ones (a live change lasts until a reload).
  void reload_config();

  // A state change, logged and told to systemd; a calibration ends outside Idle.
  Transition transition(StateEvent event, const char* cause);
  // A command's state change: refused with the state machine's reason.
  CommandResult request(StateEvent event, const char* what);
  // Start while Starting: kept until the loops run (the bus appears before they have).
  CommandResult start();
  // Stop: cancels a calibration or a Start kept while Starting before it stops spraying.
  CommandResult stop();
  // Each tick: Starting ends once both loops have run a cycle (then daemon.autostart, or a
  // Start kept meanwhile; not after an unfinished run).
  void finish_starting(const PressureStatus& pressure, const ControlStatus& control,
                       bool previous_run_unfinished);
  // Each tick: a press of the start/stop key (when one is wired) starts or stops spraying.
  void follow_key();
  // Each tick: a running calibration fed, its valves and results published.
  void update_calibration();

  void publish_params();

 private:
  const Config& config_;
  const Backends& backends_;
  Sprayer* sprayer_ = nullptr;
  Nanos start_time_{};
  std::function<void()> published_;
  StateMachine state_;
  std::optional<Calibrations> calibrations_;
  double setpoint_mpa_;
  double decision_threshold_;
  double nominal_flow_l_per_min_;
  std::uint64_t trip_reset_ = 0;
  bool start_when_ready_ = false;  // Start arrived while Starting
  std::uint64_t key_changes_ = 0;
};

}  // namespace weedspray::daemon
