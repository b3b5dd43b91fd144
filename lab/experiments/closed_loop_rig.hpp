// SPDX-License-Identifier: Apache-2.0
// The simulated machine the experiments run on: the hydraulic plant with the daemon's control
// steps around it, in simulated time (like a vehicle's code under SITL, the steps do not know).
//
//   pressure sensor volts -> ADC counts -> 4-20 mA -> MPa (io/signal_conversion.hpp, with its
//   fault rule) -> control::PressureLoopStep -> DAC -> return valve, pump
//   requested flows -> control::NozzleCommandStep (calibrated lines at sqrt(Pcal/P), the law's
//   band, the flow trim) on the daemon's control-loop period -> duties
//   -> PwmSchedule (the daemon's pwm_config) -> exact valve edges -> plant
//   valve edges + meter -> control::PhaseWindows (kMeterLag) -> NozzleHealth
//
// The settings the daemon has in its configuration (gains, pressure loop rate, valve minimum
// on/off times, the over-pressure trip) default to the daemon's defaults
// (daemon/sprayer/step_settings.hpp); an experiment changes them only where it says so.
//
// Every "fix" of the papers is a switch here (RigFixes), so each experiment can run with and
// without them on the same plant and seed. Pure: no clocks, no threads.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "control/calibration.hpp"
#include "control/flow_feedback.hpp"
#include "control/flow_trim_step.hpp"
#include "control/nozzle_command_step.hpp"
#include "control/nozzle_health.hpp"
#include "control/phase_windows.hpp"
#include "control/pressure_loop_step.hpp"
#include "control/pwm_schedule.hpp"
#include "control/spray_rate_law.hpp"
#include "lab/experiments/boom_trim.hpp"
#include "lab/experiments/phase_window_fit.hpp"
#include "lab/experiments/vocabulary.hpp"
#include "sim/plant/hydraulic_plant.hpp"

namespace weedspray::lab::experiments {

// Fuzzy-PID and PID settings found by the documented search of step_response.hpp
// (`weedspray-lab experiment step --tune` reruns it). Output u in [0, 1] closes the return
// valve: volts = 10 (1 - u).
FuzzyPidConfig default_fuzzy_pid_config();
PidGains default_conventional_pid_gains();

// The daemon's pressure loop from its default configuration ([pressure]: controller, gains,
// loop_hz), and its [pwm] and [alarms] defaults the rig takes.
const PressureLoopConfig& daemon_pressure_loop_config();
double daemon_pwm_min_on_s();
double daemon_pwm_min_off_s();
double daemon_over_pressure_mpa();
double daemon_control_loop_period_s();

// The fixes of the papers that can be switched off to show the raw machine.
struct RigFixes {
  bool staggered = true;              // staggered PWM phases (else synchronous)
  bool pressure_compensation = true;  // duty from the calibrated line at sqrt(Pcal/P)
  bool flow_feedback = true;          // FlowTrim on the (calibrated) meter
  // With flow_feedback: BoomTrim (the meter against the lines' promise as a model: common
  // gain and valve timing) instead of FlowTrim (1 / the metered ratio). Not the default: it
  // under-doses sparse variable-rate fields (boom_trim.hpp).
  bool model_trim = false;
};

struct RigConfig {
  plant::PlantParams plant{};
  std::uint64_t seed = 1;
  PressureControlMode controller_mode = daemon_pressure_loop_config().mode;
  FuzzyPidConfig controller = daemon_pressure_loop_config().controller;
  double setpoint_mpa = 0.2;
  // The pressure loop's period.
  double control_period_s = daemon_pressure_loop_config().period_s;
  // The control loop's period: the duties and the trim are stepped on this tick.
  double command_period_s = daemon_control_loop_period_s();
  double over_pressure_mpa = daemon_over_pressure_mpa();  // the pressure step trips above it
  // The daemon's converters' thread (io::AnalogIoWorker): the ADC is sampled this long before
  // each control tick and the DAC written this long after it. 0 = at the tick (ideal I/O).
  double converter_lead_s = 0.0;
  double converter_lag_s = 0.0;
  // What the controller believes about its sensor (the label values, not the plant's truth).
  double sensor_full_scale_mpa = 1.0;
  double sensor_shunt_ohms = 165.0;
  int adc_bits = 12;
  double adc_reference_volts = 3.3;
  double pwm_frequency_hz = 3.0;
  double pwm_min_on_s = daemon_pwm_min_on_s();
  double pwm_min_off_s = daemon_pwm_min_off_s();
  RigFixes fixes{};
  // Flow meter K-factor the controller uses (label 8500 until a catch test replaced it).
  double meter_pulses_per_l = 8500.0;
  FlowTrimConfig flow_trim{};
  double flow_trim_window_s = 1.0;  // meter reading averaged over this window (FlowTrim)
  // The spray law's duty clamp (< min -> 0, > max -> 100), applied to requested flows' duties.
  std::optional<SprayLawConfig> duty_clamp{};
  // The daemon's duty quantiser ([spray] quantiser_levels, hysteresis_pct). Off by default:
  // the experiments ask for exact flows and judge the plant and the trim, not the levels.
  bool quantise = false;
  // Flows between the band's top and the held-open flow alternate whole PWM periods (the
  // daemon's step); false: held open, as a plain clamp does.
  bool alternate_periods = true;
  // Time constant of the pressure filter the compensation uses (noise would otherwise jitter
  // the duties): the trim's.
  double compensation_filter_s = PressureFilter::kTimeConstantS;
  double ground_speed_m_per_s = 1.0;
  double record_period_s = 0.005;  // 0 = no trace
  // Per-nozzle health from the line meter, fed one window per PWM phase (period / nozzles,
  // aligned to the PWM start) by the daemon's PhaseWindows, the meter read kMeterLag late.
  std::optional<NozzleHealthConfig> nozzle_health{};
  BoomTrimConfig boom_trim{};  // fixes.model_trim
  // Fit each nozzle's metered / promised ratio from the same phase windows (PhaseWindowFit, a
  // lab diagnostic: it changes no duty).
  bool identify_nozzles = false;
};

struct TraceSample {
  double time_s = 0.0;
  double pressure_mpa = 0.0;           // true line pressure (manifold, where the sensor is)
  double boom_pressure_mpa = 0.0;      // true pressure at the boom's first tap
  double measured_pressure_mpa = 0.0;  // what the controller saw
  double total_flow_l_per_min = 0.0;   // true nozzle total
  double return_valve_volts = 0.0;
  std::uint32_t valve_mask = 0;
};

class ClosedLoopRig {
 public:
  // Throws std::invalid_argument (from the parts) on a bad config.
  explicit ClosedLoopRig(const RigConfig& config);

  // Nozzle lines used when the fixes are on (calibrate first; see calibration_experiment).
  void set_nozzle_lines(std::span<const NozzleLine> lines);
  // Calibrated flow with the valve held open [L/min], passed to the spray-rate law as the
  // lines' full_open_flow_l_per_min (a request at or above it opens the valve fully; see
  // spray_rate_law.hpp). Overrides the lines' own value where > 0.
  void set_full_open_flows(std::span<const double> flow_l_per_min);
  // Ask for a flow per nozzle [L/min]; converted to duties via the calibrated lines.
  void request_flows(std::span<const double> flow_l_per_min);
  // Command duties directly [%] (raw machine, or calibration runs); stops flow requests.
  void command_duties(std::span<const double> duty_pct);
  // Pump on, controller enabled from a fully open return valve, PWM started at the current
  // time. Called once.
  void start();
  // Advance simulated time; handles PWM edges and control ticks exactly on their instants.
  void run_for(double seconds);

  plant::HydraulicPlant& plant() { return plant_; }
  const plant::HydraulicPlant& plant() const { return plant_; }
  const std::vector<TraceSample>& trace() const { return trace_; }
  void clear_trace() { trace_.clear(); }
  double time_s() const { return plant_.time_s(); }
  double measured_pressure_mpa() const { return measured_pressure_mpa_; }
  double flow_trim_correction() const { return command_step_.outputs().trim.correction; }
  std::array<double, plant::kMaxNozzles> commanded_duties_pct() const { return duties_; }
  const RigConfig& config() const { return config_; }
  // The detector (config.nozzle_health set), else nullptr.
  const NozzleHealth* nozzle_health() const { return health_ ? &*health_ : nullptr; }
  // The largest NozzleHealth::evidence of any nozzle after any window so far (its CUSUMs move
  // every window, between the experiment's samples).
  double health_max_evidence() const { return health_max_evidence_; }
  // identify_nozzles: the fit, and each nozzle's promise (the lines at the latched duties) [L],
  // both since the last restart_identification().
  const PhaseWindowFit* nozzle_fit() const { return fit_ ? &*fit_ : nullptr; }
  double identification_promised_l(int nozzle) const {
    return fit_promised_l_[static_cast<std::size_t>(nozzle)];
  }
  void restart_identification();

 private:
  void control_tick();
  // The nozzle-health windows at `now` (the daemon's PhaseWindows, fed the rig's exact edges).
  void update_health_windows();
  void fit_window_closed();
  // The fit's windows: each nozzle's promised volume over step_s.
  void account_open_time(double step_s);
  void valve_edge(std::uint32_t mask);  // applies an edge's valve states
  // The daemon's duty step for the requested flows; dt_s > 0 (a control-loop tick) steps the
  // flow trim too.
  void apply_flow_requests(double dt_s);
  // Commanded duties held (a calibration, a re-check): the daemon's step told not to spray.
  void step_not_spraying(double dt_s);
  // The step's inputs but the targets and lines: the rig's fixes, pressure and meter now.
  NozzleCommandInputs command_inputs(double dt_s, bool spraying) const;
  void set_pwm_duties();
  struct PressureReading {
    double pressure_mpa = 0.0;
    bool ok = false;  // inside the sensor's fault limits
  };
  PressureReading read_pressure() const;
  double read_pressure_mpa();  // read_pressure(), its fault into sensor_ok_
  double next_edge_time_s() const;

  RigConfig config_;
  plant::HydraulicPlant plant_;
  PressureLoopStep pressure_step_;
  PwmSchedule pwm_;
  NozzleCommandStep command_step_;
  PressureFilter boom_trim_pressure_;  // what the model trim judges the set-point by
  std::array<NozzleLine, plant::kMaxNozzles> lines_{};
  std::array<double, plant::kMaxNozzles> requested_flows_{};
  std::array<double, plant::kMaxNozzles> full_open_flows_{};
  std::array<double, plant::kMaxNozzles> promised_flows_{};  // law's flow for the chosen duty
  // The lines' promise at the duties latched (after the trim): FlowTrim's reference.
  std::array<double, plant::kMaxNozzles> commanded_promise_{};
  std::array<double, plant::kMaxNozzles> duties_{};
  bool flows_requested_ = false;
  bool started_ = false;
  PwmEdge pending_edge_{};
  std::uint32_t applied_mask_ = 0;
  double next_control_s_ = 0.0;
  double next_command_s_ = 0.0;
  double next_sample_s_ = 0.0;  // converter_lead_s > 0: the next ADC sample
  double sampled_pressure_mpa_ = 0.0;
  double dac_due_s_ = -1.0;  // converter_lag_s > 0: when the pending DAC write lands (< 0: none)
  double dac_pending_volts_ = 0.0;
  double next_record_s_ = 0.0;
  double pwm_start_s_ = 0.0;
  double measured_pressure_mpa_ = 0.0;
  bool sensor_ok_ = true;
  std::vector<TraceSample> trace_;
  std::optional<NozzleHealth> health_;
  std::optional<BoomTrim> boom_trim_;
  std::optional<PhaseWindowFit> fit_;
  std::array<double, plant::kMaxNozzles> fit_promised_l_{};
  std::optional<PhaseWindows> health_windows_;
  double last_edge_s_ = 0.0;                                    // when the valve mask last changed
  std::array<double, plant::kMaxNozzles> window_promised_l_{};  // in the fit's window being cut
  std::uint64_t fit_pulses_ = 0;  // meter pulses at the fit's last window
  // Each nozzle's flowing interval by its valve's label timing: the pulse now and the one
  // before it (its tail can run into the next opening).
  using Interval = std::pair<double, double>;
  std::array<Interval, plant::kMaxNozzles> flow_previous_{};
  std::array<Interval, plant::kMaxNozzles> flow_current_{};
  BoomTrimWindows boom_trim_windows_{};
  std::array<double, plant::kMaxNozzles> line_slopes_{};  // dL/dd now [L/min per % duty]
  double phase_window_s_ = 0.0;
  double next_fit_window_s_ = -1.0;  // end of the fit's window being cut
  double health_max_evidence_ = 0.0;
};

}  // namespace weedspray::lab::experiments
