// SPDX-License-Identifier: Apache-2.0
// The calibrations run from the daemon, step by step on the main thread (no real-time work:
// the control loop only executes the valve duties this asks for, and counts the meter).
//   Catch test: every valve open for a set time with the pump holding the set-point, then
//     closed; the meter's pulses over the run (plus a short drain after closing) wait for the
//     volume the user collected and measured: pulses / volume = the meter's pulses per litre.
//   Nozzle sweep: each nozzle alone at each duty of the plan; at each point the first settle_s
//     is skipped (valve, pressure and meter settling), the next measure_s counted; the flow
//     pulses / K / minutes, fitted per nozzle with control::fit_nozzle_line.
// Pure (time and pulse counts are inputs), so tests drive it with made-up meters.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "control/calibration.hpp"
#include "io/valve_pwm_driver.hpp"

namespace weedspray::daemon {

// kValveTest, kPumpTest: the commissioning checks (sprayctl test), run and guarded as the
// calibrations are.
enum class CalibrationState {
  kIdle,
  kCatchTest,
  kAwaitingVolume,
  kNozzles,
  kValveTest,
  kPumpTest,
  kDone,
  kCancelled
};
const char* to_string(CalibrationState state) noexcept;

struct NozzleSweepPlan {
  std::vector<double> duties_pct{20.0, 40.0, 60.0, 80.0};  // >= 2 distinct, inside 0..100
  double settle_s = 2.0;
  double measure_s = 5.0;
  double pressure_mpa = 0.4;         // the set-point the sweep runs at (the lines' P_cal)
  double pulses_per_litre = 8500.0;  // the meter's K in use
  // One point more per nozzle, held open (100 %): the line's full_open_flow_l_per_min (not
  // fitted: a valve held open is not the pulsed line extrapolated to 100 %; in the simulator
  // one nozzle held open read 1-7 % under it, 0.90-0.96 against ~0.97 L/min).
  bool full_open = true;
};

class CalibrationRun {
 public:
  // After the catch test closes the valves the meter still counts the liquid in the line.
  static constexpr double kDrainS = 0.5;
  // The pump runs only while spraying or calibrating: the sweep's first point waits this long
  // more for the pressure loop to reach the set-point (the sim's takes ~1 s from cold).
  static constexpr double kPumpLeadInS = 2.0;

  explicit CalibrationRun(std::size_t nozzles);

  // Each returns "" when started, else why not (another calibration runs, a bad argument).
  std::string start_catch_test(double duration_s, double now_s, std::uint64_t pulses);
  std::string start_nozzle_sweep(const NozzleSweepPlan& plan, double now_s, std::uint64_t pulses);
  // The measured volume of a finished catch test: the meter's calibration against
  // `configured_pulses_per_litre`; nullopt and `error` set unless a catch test awaits it, or
  // when the result is further than `max_change_pct` from the configured K (a typo in the
  // volume: the catch test still awaits the right one).
  std::optional<control::FlowMeterCalibration> enter_volume(double volume_l,
                                                            double configured_pulses_per_litre,
                                                            double max_change_pct,
                                                            std::string& error);
  // Commissioning (output_tests.cpp). A valve test holds `nozzle` at `duty_pct` for
  // `duration_s` (1..60 s) with the pump on, then reports the meter's pulses over it
  // (`pulses_per_litre` 0: no meter). A pump test runs the pump holding `setpoint_mpa` with
  // every valve closed for `duration_s` (1..120 s), then reports the pressure it reached
  // (observe_pressure() each tick). Each returns "" when started, else why not.
  std::string start_valve_test(std::size_t nozzle, double duty_pct, double duration_s, double now_s,
                               std::uint64_t pulses, double pulses_per_litre);
  std::string start_pump_test(double duration_s, double now_s, double setpoint_mpa);
  void observe_pressure(double now_s, double pressure_mpa) noexcept;

  // Ends a running calibration (or a catch test awaiting its volume): valves closed.
  void cancel(std::string_view why);
  // Every main-loop tick: the time and the meter's pulse count.
  void update(double now_s, std::uint64_t pulses);

  // True while the calibration commands the valves (duties()) and runs the pump.
  bool running() const noexcept {
    return state_ == CalibrationState::kCatchTest || state_ == CalibrationState::kNozzles ||
           state_ == CalibrationState::kValveTest || state_ == CalibrationState::kPumpTest;
  }
  const std::array<double, io::kMaxValves>& duties() const noexcept { return duties_; }
  CalibrationState state() const noexcept { return state_; }
  double progress() const noexcept { return progress_; }
  const std::string& message() const noexcept { return message_; }
  std::uint64_t catch_test_pulses() const noexcept { return catch_pulses_; }
  // The sweep's fits once done (index = nozzle; nullopt where no line could be fitted). Taken
  // once: the daemon stores them.
  std::vector<std::optional<control::NozzleLineFit>> take_fits();

 private:
  void set_point_duty();
  void finish_nozzle();
  std::size_t points_per_nozzle() const noexcept;
  void update_output_test(double now_s, std::uint64_t pulses);
  void finish_valve_test(std::uint64_t pulses);
  void finish_pump_test();
  double point_duty_pct(std::size_t point) const noexcept;

  std::size_t nozzles_;
  CalibrationState state_ = CalibrationState::kIdle;
  double progress_ = 0.0;
  std::string message_ = "no calibration run yet";
  std::array<double, io::kMaxValves> duties_{};
  // Catch test.
  double started_s_ = 0.0;
  double duration_s_ = 0.0;
  std::uint64_t start_pulses_ = 0;
  std::uint64_t catch_pulses_ = 0;
  // Valve and pump tests (started_s_, duration_s_, start_pulses_ too).
  std::size_t tested_nozzle_ = 0;
  double tested_duty_pct_ = 0.0;
  double test_pulses_per_litre_ = 0.0;
  double test_setpoint_mpa_ = 0.0;
  double peak_pressure_mpa_ = 0.0;
  double reached_after_s_ = -1.0;  // first time within 5 % of the set-point; < 0: not yet
  // Nozzle sweep.
  NozzleSweepPlan plan_;
  std::size_t nozzle_ = 0;
  std::size_t point_ = 0;
  bool measuring_ = false;
  double phase_start_s_ = 0.0;
  std::uint64_t phase_pulses_ = 0;
  std::vector<control::DutyFlowPoint> points_;
  std::vector<std::optional<control::NozzleLineFit>> fits_;
};

}  // namespace weedspray::daemon
