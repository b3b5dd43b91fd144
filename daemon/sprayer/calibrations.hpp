// SPDX-License-Identifier: Apache-2.0
// The daemon's side of the calibrations (main thread): the D-Bus commands, the run
// (calibration_run.hpp) fed each tick, the results stored in the state directory
// (records/calibration_store.hpp) and what the loops use from them (LiveParams: the meter's K,
// each nozzle's line, the valves during a run).
// Calibrations run only in Idle (pump holding the set-point, nothing sprayed): refused while
// spraying or while another runs, cancelled by Stop or by leaving Idle, valves closed after.
#pragma once

#include <array>
#include <filesystem>
#include <functional>

#include "daemon/bus/status.hpp"
#include "daemon/config/config.hpp"
#include "daemon/records/calibration_store.hpp"
#include "daemon/sprayer/calibration_run.hpp"
#include "daemon/sprayer/runtime_types.hpp"

namespace weedspray::daemon {

// What the commands need to know of the sprayer now.
struct CalibrationContext {
  bool idle = false;        // state Idle (pump on, valves the daemon's)
  bool have_meter = false;  // a flow meter is wired
  double now_s = 0;
  std::uint64_t pulses = 0;  // the meter's count (ControlStatus::flow_pulses)
  double setpoint_mpa = 0;
  double pressure_mpa = 0;  // the line pressure now (the pump test's measure)
};

class Calibrations {
 public:
  // Loads <state_dir>/calibration.toml (a corrupt file is logged and ignored).
  // `sim_delivered_l`: in a simulation, the plant's true delivered volume, so the catch test
  // can log the volume a user would have collected; empty on hardware.
  Calibrations(const Config& config, const std::filesystem::path& state_dir,
               std::function<double()> sim_delivered_l = {});

  CommandResult start_catch_test(double seconds, const CalibrationContext& context);
  CommandResult calibrate_meter(double volume_l);
  CommandResult calibrate_nozzles(const CalibrationContext& context);
  // Commissioning: one valve at a duty, or the pump alone (calibration_run.hpp).
  CommandResult test_valve(std::uint32_t nozzle, double duty_pct, double seconds,
                           const CalibrationContext& context);
  CommandResult test_pump(double seconds, const CalibrationContext& context);
  // Stop: true when a calibration was running (or awaiting its volume) and is now cancelled.
  bool cancel(const char* why);
  bool running() const noexcept { return run_.running(); }

  // Every tick. True when the loops' parameters changed (valves, a new result): publish them.
  bool update(const CalibrationContext& context);
  // The configuration reloaded ([spray] line, meter K, min R^2 may have changed).
  void set_config(const Config& config);

  // The meter K, each nozzle's line and the calibration's valves into the loops' parameters.
  void apply(LiveParams& params) const;
  void fill_status(Status& status) const;

 private:
  void refresh_choices();
  void save() noexcept;

  control::NozzleLine configured_line_{};   // [spray]
  double configured_pulses_per_litre_ = 0;  // flow.pulses_per_litre
  CalibrationSection section_{};
  std::filesystem::path file_;
  std::function<double()> sim_delivered_l_;
  double catch_test_delivered_at_start_l_ = 0;
  StoredCalibration stored_;
  CalibrationRun run_;
  std::size_t nozzles_;
  std::array<NozzleLineChoice, io::kMaxValves> choices_{};
};

}  // namespace weedspray::daemon
