// SPDX-License-Identifier: Apache-2.0
// The papers' experiments, rerun on the simulated machine (closed_loop_rig.hpp). Each returns
// a plain result struct with its time series / points, for tables, JSON, plots and tests.
// Volumes are judged against the plant's TRUE delivered volume, never the simulated meter.
// Pure: no I/O, simulated time only; deterministic for a given seed.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "control/nozzle_recheck.hpp"
#include "control/spray_rate_law.hpp"
#include "lab/experiments/closed_loop_rig.hpp"
#include "lab/experiments/machines.hpp"
#include "lab/experiments/metrics.hpp"
#include "lab/experiments/vocabulary.hpp"
#include "sim/field/field_duty_process.hpp"

namespace weedspray::lab::experiments {

// ---------- step: start-up 0 -> 0.2 MPa, PID vs fuzzy PID (UGV Fig. 7) ----------
struct StepRun {
  StepMetrics metrics{};
  PidGains gains{};  // conventional: the gains; fuzzy: the base gains
  std::vector<TraceSample> trace;
};
struct StepResult {
  StepRun pid;
  StepRun fuzzy_pid;
  PidGains fuzzy_correction_weights{};
  double setpoint_mpa = 0.2;
};
struct StepOptions {
  std::uint64_t seed = 1;
  double setpoint_mpa = 0.2;
  double duration_s = 3.0;
  PidGains pid_gains = default_conventional_pid_gains();
  FuzzyPidConfig fuzzy = default_fuzzy_pid_config();
  // The pressure loop's timing (RigConfig): period, and the converters' thread's ADC lead and
  // DAC lag around each tick.
  double control_period_s = 0.005;
  double converter_lead_s = 0.0;
  double converter_lag_s = 0.0;
  // The machine (PlantParams{} = the ideal bench) and how many nozzles spray (< 0: all).
  plant::PlantParams plant{};
  int nozzles_open = -1;
};
StepResult run_step(const StepOptions& options);
StepRun run_step_once(PressureControlMode mode, const FuzzyPidConfig& config,
                      const StepOptions& options);

// The documented tuning search: a coarse-to-fine grid over (Kp, Ki, Kd) minimising ITAE for
// the conventional PID; then, for the fuzzy PID, the same search over its base gains and a
// grid of correction weights (Cp, Ci, Cd). Each candidate is one 3 s simulated start-up.
struct TuningResult {
  PidGains pid{};
  StepMetrics pid_metrics{};
  FuzzyPidConfig fuzzy{};
  StepMetrics fuzzy_metrics{};
  int candidates_evaluated = 0;
};
TuningResult tune_step_controllers(const StepOptions& options);

// ---------- ripple: 4 nozzles 50 %, 3 Hz, synchronous vs staggered (UGV Fig. 8) ----------
struct RippleRun {
  double pp_mpa = 0.0;       // peak-to-peak true line pressure (manifold) after settling
  double boom_pp_mpa = 0.0;  // the same at the boom (water hammer of closing valves)
  std::vector<TraceSample> trace;
};
struct RippleResult {
  RippleRun synchronous;
  RippleRun staggered;
};
struct RippleOptions {
  std::uint64_t seed = 1;
  double duty_pct = 50.0;
  double frequency_hz = 3.0;
  double settle_s = 5.0;
  double measure_s = 5.0;
  plant::PlantParams plant{};  // PlantParams{} = the ideal bench (smooth pump)
};
RippleResult run_ripple(const RippleOptions& options);

// ---------- calibration: meter catch test + per-nozzle lines (SPEC §2/§4) ----------
struct NozzleCalibration {
  NozzleLine fitted{};  // from the ONE line flow meter, with the calibrated K-factor
  NozzleLine truth{};   // the same fit on the plant's TRUE delivered volumes
  double r_squared = 0.0;
  // Flow with the valve held open (100 %), metered and true. Not the line at 100 %: near full
  // duty the off-time gets shorter than the valve's closing delay and the line stops holding.
  double full_open_l_per_min = 0.0;
  double true_full_open_l_per_min = 0.0;
};
struct CalibrationResult {
  FlowMeterCalibration meter{};
  double true_pulses_per_litre = 0.0;
  double meter_k_error_pct = 0.0;  // (nominal label - true) / true * 100 as the catch test saw
  double meter_calibration_error_pct = 0.0;  // (calibrated - true) / true * 100
  double jug_error_pct = 0.0;  // the catch-test jug's reading error drawn for this machine
  std::vector<NozzleCalibration> nozzles;
};
struct CalibrationOptions {
  std::uint64_t seed = 1;
  double pressure_mpa = 0.2;
  double frequency_hz = 3.0;
  double catch_test_s = 60.0;
  std::vector<double> duties_pct{20, 30, 40, 50, 60, 70, 80};
  double settle_s = 2.0;
  double measure_s = 20.0;
  plant::PlantParams plant{};  // the machine calibrated (PlantParams{} = the ideal bench)
  std::optional<MachineChange> change{};  // applied before calibrating: a recalibration
  // The catch test's collected volume is read off a jug, off by a fraction drawn uniform in
  // +-jug_error_limit per machine (from `seed`; the same jug when it recalibrates): a user's
  // graduated jug reads within about +-0.8 %. 0: the plant's true volume.
  double jug_error_limit = 0.008;
};
CalibrationResult run_calibration(const CalibrationOptions& options);

// ---------- linearity: nozzle 1 swept 10-100 %, others 100 % (UGV Fig. 9) ----------
struct DutyPoint {
  double duty_pct = 0.0;
  double commanded_duty_pct = 0.0;  // after calibration / compensation / trim
  // Asked over the run: the duty's share of the reference flow at the reference speed, times
  // the ground speed over the reference speed (speed_target.hpp), at most the full-open flow.
  double requested_l = 0.0;
  double clipped_l = 0.0;    // the speed-following target above the full-open flow: not asked
  double delivered_l = 0.0;  // TRUE
  double error_pct = 0.0;    // |delivered - requested| / requested * 100
};
struct LinearityResult {
  std::vector<DutyPoint> points;
  double r2 = 0.0;  // delivered volume vs duty
  double mean_error_pct = 0.0;
  double max_error_pct = 0.0;
  bool raw = false;
};
struct SprayRunOptions {
  std::uint64_t seed = 1;
  double pressure_mpa = 0.2;
  double frequency_hz = 3.0;
  double settle_s = 3.0;
  double run_s = 30.0;
  // raw: no calibration (duty commanded as asked), no pressure compensation, no flow
  // feedback, synchronous PWM. Otherwise the machine is calibrated first (run_calibration).
  bool raw = false;
  // The machine (PlantParams{} = the ideal bench), calibrated as made; `change` is applied
  // after the calibration, before each test run (ramps over the measured window).
  plant::PlantParams plant{};
  std::optional<MachineChange> change{};
  bool flow_feedback = true;  // online flow trim (not raw)
  // ...as a model (BoomTrim: common gain and valve timing) or FlowTrim, 1 / the metered ratio
  // (the daemon's).
  bool model_trim = false;
  // Calibrate after `change`, not before it (a user recalibrating the changed machine); the
  // requested volume stays the calibration as made (the job's target).
  bool recalibrated = false;
  // Also fit each nozzle's ratio from the phase windows (PhaseWindowFit; orthogonal only).
  bool identify_nozzles = false;
  // A headland before each run, after the change (not raw): control::NozzleRecheck holds each
  // nozzle open alone, reads it against its calibrated held-open flow and rescales its line
  // (scaled_line), as the daemon does; then the run's flows are asked of the rescaled lines.
  // The requested volume stays the calibration's (the reading moves the lines, not the target).
  bool headland_recheck = false;
  NozzleRecheckConfig recheck_config{};
  double recheck_pressure_tolerance_mpa = 0.02;
  // The daemon's flow trim settings (control::FlowTrimStep, which the rig runs).
  FlowTrimConfig flow_trim{};
  // The duties are each nozzle's demand at the reference speed; follow_speed: every control
  // period the target is the demand times the ground speed (the change's ramp, else the
  // reference) over the reference speed, through the daemon's rate law, clipped at the
  // reference's full-open flow (the calibration as made: recalibrated, a nozzle that lost flow
  // is still asked it) (speed_target.hpp). false: the duty's flow whatever the speed.
  bool follow_speed = true;
  double reference_speed_m_per_s = 1.0;
};
LinearityResult run_linearity(const SprayRunOptions& options);

// ---------- orthogonal: the 16 L16 runs of SPEC §3 ----------
inline constexpr std::array<std::array<double, 4>, 16> kOrthogonalL16 = {{
    {25, 25, 25, 25},
    {25, 50, 50, 50},
    {25, 75, 75, 75},
    {25, 100, 100, 100},
    {50, 25, 50, 75},
    {50, 50, 25, 100},
    {50, 75, 100, 25},
    {50, 100, 75, 50},
    {75, 25, 75, 100},
    {75, 50, 100, 75},
    {75, 75, 25, 50},
    {75, 100, 50, 25},
    {100, 25, 100, 50},
    {100, 50, 75, 25},
    {100, 75, 50, 100},
    {100, 100, 25, 75},
}};
struct OrthogonalRun {
  std::array<DutyPoint, 4> nozzles{};
  double pressure_band_mpa = 0.0;  // largest |P - set-point| after start-up
  // identify_nozzles: |fitted ratio / true ratio - 1| x 100 per nozzle, the true ratio being
  // its true volume over what its line promised at the latched duties in the measured window.
  std::array<double, 4> identification_error_pct{};
};
struct OrthogonalResult {
  std::vector<OrthogonalRun> runs;
  double mean_error_pct = 0.0;
  double max_error_pct = 0.0;
  // ...over the nozzle-runs below 100 % duty: a nozzle held open cannot be trimmed up, so a
  // blocked one there sprays its blockage short whatever the controller does.
  double max_error_modulated_pct = 0.0;
  double pressure_band_mpa = 0.0;
  bool raw = false;
  // identify_nozzles: over the nozzle-runs below 100 % duty (held-open ones share one column)
  double mean_identification_error_pct = 0.0;
  double max_identification_error_pct = 0.0;
  // The speed-following target's volume above the full-open flows, % of the law's volume.
  double clipped_pct = 0.0;
};
OrthogonalResult run_orthogonal(const SprayRunOptions& options);

// The floor of the L16 on a changed machine for any controller that holds a nozzle asked for
// 100 % open (the L16's 100 % level) and one line pressure: from the plant's truth in steady
// flow (no valve timing, water hammer or meter error), the other nozzles spraying exactly what
// they are asked, and the pressure the one common knob, within the band (set-point
// +-0.02 MPa; flow goes with its square root). Per run, the pressure that balances the
// held-open nozzles' highest and lowest flow against the reference (each nozzle's calibrated
// full-open flow, as in run_orthogonal) leaves the smaller of their worst errors; the floor is
// the largest over the 16 runs [%]. Going below it needs a held-open nozzle pulsed below 100 %,
// that is, knowing which nozzle changed.
double orthogonal_held_open_floor_pct(const SprayRunOptions& options);

// The floor of the L16's MEAN error on a changed machine for any boom-wide law that believes
// its meter: from the same steady plant truth, per run one common factor for the modulated
// nozzles and the pressure within the band for the held-open ones, each chosen with hindsight
// to minimise the run's summed |error| as the meter shows it (its drift scales every reading
// alike and only a catch test sees it); the mean TRUE error over the 64 nozzle-runs [%].
// Optimistic: it ignores valve timing, water hammer and the pump.
double orthogonal_common_floor_pct(const SprayRunOptions& options);

// Per-nozzle full-open flow the calibrated machine believes in (metered at 100 %), shared by
// linearity/orthogonal to define "requested".
std::vector<double> calibrated_full_flows(const CalibrationResult& calibration);

// ---------- dose: wheat paper's check, densities 0.40-0.75 at 1 m/s, 0.4 MPa, 5 Hz ----------
struct DosePoint {
  double density = 0.0;
  // 60 D w v u / k over the run (the mean of the speed-following target, clipped at the
  // full-open flow), nozzle 1
  double theoretical_l_per_min = 0.0;
  double delivered_l_per_min = 0.0;  // TRUE, nozzle 1
  double duty_pct = 0.0;
  double clipped_l_per_min = 0.0;  // the law's flow above the full-open flow, over the run
};
struct DoseResult {
  std::vector<DosePoint> points;
  double r2 = 0.0;  // delivered vs theoretical
  double mean_error_pct = 0.0;
};
struct DoseOptions {
  std::uint64_t seed = 1;
  double pressure_mpa = 0.4;
  double frequency_hz = 5.0;
  double speed_m_per_s = 1.0;
  // k = 0.75: the densest zone gets q_nom; with it the theoretical flows span 0.33-0.62 L/min,
  // the range the paper measured (0.32-0.61).
  double max_density = 0.75;
  std::vector<double> densities{0.40, 0.45, 0.50, 0.55, 0.60, 0.65, 0.70, 0.75};
  double settle_s = 3.0;
  double run_s = 60.0;
  // The machine (PlantParams{} = the ideal bench), calibrated as made; `change` is applied
  // after the calibration, before each density's run (ramps over the measured minute). Its
  // ground speed ramp replaces speed_m_per_s.
  plant::PlantParams plant{};
  std::optional<MachineChange> change{};
  bool flow_feedback = true;  // online flow trim
  // Each control period the law's target at the ground speed then (speed_target.hpp), clipped
  // at the nozzle's full-open flow; false: at speed_m_per_s whatever the ground speed.
  bool follow_speed = true;
};
DoseResult run_dose(const DoseOptions& options);

// ---------- savings: variable vs uniform spraying over a field of zone densities ----------
// zone_densities[z][n]: weed density of zone z (along travel) under nozzle n. The field is laid
// out as the bundled images are: each frame images two zone rows (near, then far) of
// zone_length_m each, 1-3 m ahead of the camera (UGV paper geometry: camera 1 m high, nozzles
// 1.2 m behind its nadir). The variable run goes through the real NozzleScheduler: every
// frame's densities are pinned to the ground interval it imaged when the odometer reaches the
// frame, and each nozzle is driven by the law from the density the scheduler gives for the
// ground under it (with the valve-delay lead), as the daemon does.
// Run twice: with the SPEC clamp (LowDutyPolicy::kClose: weedy zones whose duty falls below
// min_duty stay dry) and at equal coverage (kRaiseToMin: every zone above the decision
// threshold gets at least the minimum effective dose). Only the latter sprays every weed the
// uniform run sprays, so it is the honest savings figure.
struct SavingsOptions {
  std::uint64_t seed = 1;
  double pressure_mpa = 0.4;
  double frequency_hz = 5.0;
  double speed_m_per_s = 1.0;
  double zone_length_m = 1.0;
  double max_density = 0.75;
  double decision_threshold = 0.0;
  // A zone is under-dosed when it received less than this fraction of its target volume.
  double under_dose_fraction = 0.9;
  // The machine (PlantParams{} = the ideal bench), calibrated as made.
  plant::PlantParams plant{};
};
struct SavingsRun {
  LowDutyPolicy policy = LowDutyPolicy::kClose;
  double variable_l = 0.0;  // TRUE volume
  double savings_pct = 0.0;
  // Nozzle-zones that got less than under_dose_fraction of what the law decided for them.
  int under_dosed_zones = 0;
  // Nozzle-zones above the decision threshold that the law decided not to spray.
  int unsprayed_weedy_zones = 0;
  std::vector<double> zone_target_l;     // per zone (all nozzles)
  std::vector<double> zone_delivered_l;  // per zone (all nozzles)
  // What the law decided for each nozzle-zone [L]: 0 = left dry.
  std::vector<std::array<double, 4>> nozzle_zone_target_l;
  std::array<double, 4> nozzle_delivered_l{};
  std::array<double, 4> nozzle_savings_pct{};  // set by run_savings (needs the uniform run)
};
struct SavingsResult {
  // Headline figures: the equal-coverage run (copied from equal_coverage).
  double variable_l = 0.0;
  double uniform_l = 0.0;  // TRUE volume of uniform spraying at q_nom over the same track
  double savings_pct = 0.0;
  int zones = 0;  // nozzle-zones (zones along travel x nozzles)
  int under_dosed_zones = 0;
  int unsprayed_weedy_zones = 0;
  std::vector<double> zone_target_l;
  std::vector<double> zone_delivered_l;
  std::array<double, 4> nozzle_savings_pct{};
  SavingsRun equal_coverage;  // LowDutyPolicy::kRaiseToMin
  SavingsRun spec_clamp;      // LowDutyPolicy::kClose
};
SavingsResult run_savings(const std::vector<std::array<double, 4>>& zone_densities,
                          const SavingsOptions& options);
// One variable-rate run with the given low-duty policy (uniform_l for the savings figure).
SavingsRun run_savings_variable(const std::vector<std::array<double, 4>>& zone_densities,
                                const SavingsOptions& options, LowDutyPolicy policy,
                                double uniform_l);

// ---------- savings against labelled crop/weed images ----------
// True pixel shares of one nozzle-zone (from class-id masks).
struct ZoneTruth {
  double weed = 0.0;
  double crop = 0.0;
};
// What a run's decisions did to the truth. A nozzle-zone is weedy when its true weed pixels are
// at least weedy_share of it (vision-eval's rule), crop-only when it is not weedy and its crop
// pixels are at least weedy_share; sprayed = the law decided a non-zero volume for it.
struct TruthTally {
  int weedy_zones = 0;
  int weedy_left_dry = 0;  // weeds missed
  int crop_only_zones = 0;
  int crop_only_sprayed = 0;  // herbicide on the crop alone
};
// truth[z][n] in the track order of the run's zone densities. Throws std::invalid_argument when
// the run and the truth have a different number of zones.
TruthTally tally_against_truth(const SavingsRun& run,
                               const std::vector<std::array<ZoneTruth, 4>>& truth,
                               double weedy_share = 0.005);

// ---------- fleets: the same experiments over N drawn machines (machines.hpp) ----------
struct FleetOptions {
  std::uint64_t seed = 1;
  int plants = 20;
  bool changed = true;                    // apply the drawn change after calibration
  ChangeParts parts = ChangeParts::kAll;  // ...all of it or one half (orthogonal only)
};
struct OrthogonalFleetRow {
  Spread mean_error_pct;           // per machine: mean over its 64 nozzle-runs
  Spread max_error_pct;            // per machine: its worst nozzle-run
  Spread max_error_modulated_pct;  // ...of those below 100 % duty
  Spread pressure_band_mpa;
  Spread mean_identification_error_pct;  // trim_on only (identify_nozzles)
  Spread max_identification_error_pct;
  // Over every nozzle-run of every machine (64 per machine): the mean and 95th percentile of
  // the volume error [%].
  double per_nozzle_mean_error_pct = 0.0;
  double per_nozzle_p95_error_pct = 0.0;
  Spread clipped_pct;  // per machine: OrthogonalResult::clipped_pct
  std::vector<OrthogonalResult> machines;
};
struct OrthogonalFleetResult {
  OrthogonalFleetRow trim_on;     // FlowTrim (metered ratio), the daemon's
  OrthogonalFleetRow model_trim;  // BoomTrim (lab only: boom_trim.hpp says why)
  OrthogonalFleetRow trim_off;
  // The remedy the daemon offers for what no boom trim can see: the catch test and the nozzle
  // calibration run again on the changed machine (sprayctl calibrate meter / nozzles), then
  // the daemon's trim.
  OrthogonalFleetRow recalibrated;
  // The daemon's remedy without the user: the headland re-check after the change (each nozzle
  // alone against its calibrated held-open flow, its line rescaled), then the daemon's trim.
  OrthogonalFleetRow headland_recheck;
  Spread held_open_floor_pct;  // orthogonal_held_open_floor_pct() per machine
  Spread common_floor_pct;     // orthogonal_common_floor_pct() per machine
  // The ground speeds the runs went through (the changes' ramps; the reference without them).
  double speed_min_m_per_s = 0.0;
  double speed_max_m_per_s = 0.0;
};
OrthogonalFleetResult run_orthogonal_fleet(const FleetOptions& fleet,
                                           const SprayRunOptions& base = {});
struct LinearityFleetResult {
  Spread r2;  // worst = lowest
  Spread mean_error_pct, max_error_pct;
};
// Calibrated as made, tested after the drawn change, trim on.
LinearityFleetResult run_linearity_fleet(const FleetOptions& fleet,
                                         const SprayRunOptions& base = {});
struct DoseFleetRow {
  Spread r2;              // delivered vs theoretical over the densities (worst = lowest)
  Spread mean_error_pct;  // per machine: mean |delivered - theoretical| / theoretical
  Spread max_error_pct;   // per machine: its worst density
  Spread clipped_pct;     // per machine: the law's volume above the full-open flow [%]
};
struct DoseFleetResult {
  DoseFleetRow trim_on, trim_off;
  // The ground speeds the runs went through (the changes' ramps).
  double speed_min_m_per_s = 0.0;
  double speed_max_m_per_s = 0.0;
};
// Calibrated as made (0.4 MPa, 5 Hz), tested after the drawn change, trim on and off.
DoseFleetResult run_dose_fleet(const FleetOptions& fleet, const DoseOptions& base = {});
// Over drawn machines as made (no change: the track is laid out at a fixed ground speed, and
// what a change does to accuracy is what dose/orthogonal --plants measure): the headline
// (equal-coverage) figures per machine.
struct SavingsFleetResult {
  Spread savings_pct;      // worst = lowest
  Spread under_dosed_pct;  // under-dosed nozzle-zones, % of all nozzle-zones
  Spread uniform_l, variable_l;
};
SavingsFleetResult run_savings_fleet(const std::vector<std::array<double, 4>>& zone_densities,
                                     const FleetOptions& fleet, const SavingsOptions& base);
struct CalibrationFleetResult {
  Spread meter_error_pct;      // |calibrated K - true K| / true K (as made)
  Spread full_open_error_pct;  // per machine: worst nozzle |metered - true| full-open flow
  Spread line_error_pct;       // per machine: worst nozzle |fitted - true| flow at 20-80 % duty
  Spread r2;                   // per machine: lowest nozzle R^2 (worst = lowest)
};
CalibrationFleetResult run_calibration_fleet(const FleetOptions& fleet,
                                             const CalibrationOptions& base = {});
struct RippleFleetResult {
  Spread synchronous_pp_mpa, staggered_pp_mpa, ratio;
  Spread synchronous_boom_pp_mpa, staggered_boom_pp_mpa;
};
RippleFleetResult run_ripple_fleet(const FleetOptions& fleet, const RippleOptions& base = {});

// ---------- blockage: per-nozzle health from the line meter (control/nozzle_health.hpp) ----------
// Each machine is calibrated as made, then sprays variable-rate (every nozzle's requested flow
// set every redraw_s as a share of its calibrated full-open flow, staggered PWM, online trim
// on) for baseline + healthy_s with no fault (any alarm = a false alarm), then one drawn nozzle
// is blocked by `blockage` and the time until the detector names a nozzle is measured (up to
// detect_limit_s x 3, at least two headland cycles). With blocked_at_start the nozzle is
// blocked before the job starts (no healthy part): a judge that learns its baseline in the job
// takes the blockage for the nozzle's normal. The judge (`recheck`):
//   off: the passive detector of the rig (health: band or CUSUM on the phase windows);
//   on:  control::NozzleRecheck on the headlands (the window: the field's headland for the whole
//     next slice and the pump on; the pressure within pressure_tolerance_mpa of the set-point
//     for reading), driven around the rig in slices of recheck_slice_s: while it holds a nozzle
//     open every other valve is closed, and each nozzle's line is rescaled by its reading.
//     It needs headlands: with kIid duties run_blockage_fleet throws std::invalid_argument.
// A nozzle counts as named within the limit when the right one is named within detect_limit_s
// of the blockage or, on field duties, by the end of the first headland that starts after it
// (one headland cycle): the passive judges have 60 s of spraying, the re-check its headland.
// The shares (`duties`):
//   kField: a field's demand (sim::FieldDutyProcess with `field`, seeded per machine) at its
//     ground speed: correlated over seconds, shared across the boom, nozzles closed where there
//     is little to spray, every nozzle off on the headlands;
//   kIid: each share redrawn independently between 30 and 90 % every redraw_s, always open (the
//     most separable duties a detector can get).
enum class BlockageDuties { kField, kIid };
struct BlockageOptions {
  double pressure_mpa = 0.2;
  double frequency_hz = 3.0;
  double blockage = 0.2;
  double healthy_s = 600.0;
  double detect_limit_s = 60.0;
  double redraw_s = 1.0;
  BlockageDuties duties = BlockageDuties::kField;
  sim::FieldDutyOptions field{};
  NozzleHealthConfig health{};
  bool blocked_at_start = false;
  bool recheck = true;  // needs headlands: kField (run_blockage_fleet throws otherwise)
  NozzleRecheckConfig recheck_config{};
  double pressure_tolerance_mpa = 0.02;
  double recheck_slice_s = 0.01;
};
struct BlockageMachine {
  int blocked_nozzle = -1;
  int named_nozzle = -1;   // -1: none named
  double detect_s = -1.0;  // from the blockage to the alarm; < 0: none in the record
  // The limit this machine's naming is judged against: detect_limit_s or, on field duties, the
  // end of the first headland after the blockage, whichever is later [s after the blockage].
  double limit_s = 0.0;
  // recheck: whole-boom re-checks completed in the healthy part, and the blocked nozzle's last
  // reading (metered / calibrated; 1 if never read after the blockage).
  int healthy_rechecks = 0;
  double blocked_ratio = 1.0;
  // recheck: the largest |reading - 1| of any nozzle in the healthy part (the readings' scatter
  // on a healthy machine: what the alarm limit must clear).
  double healthy_reading_deviation = 0.0;
  bool false_alarm = false;  // an alarm during the healthy part
  // The shares requested during the healthy part: the fraction of nozzle-redraws closed (0),
  // and the correlation of a nozzle's share with its share one redraw later (pooled over the
  // nozzles; ~0 for independent redraws).
  double closed_share = 0.0;
  double share_lag_correlation = 0.0;
  // Largest |ratio - 1| of any nozzle during the healthy part (sampled every redraw): the
  // detector's scatter on this machine, what the alarm fraction must clear.
  double healthy_worst_deviation = 0.0;
  // Largest evidence (NozzleHealth::evidence, the CUSUMs) of any nozzle after any window of
  // the healthy part: what alarm_threshold must clear.
  double healthy_max_evidence = 0.0;
};
struct BlockageFleetResult {
  std::vector<BlockageMachine> machines;
  int named_within_limit = 0;  // the blocked nozzle named within its machine's limit_s
  int false_alarms = 0;
  Spread detect_s;  // over the machines that named the right nozzle
  Spread healthy_worst_deviation;
  Spread healthy_max_evidence;
  Spread healthy_reading_deviation;  // recheck
  double healthy_minutes = 0.0;
};
BlockageFleetResult run_blockage_fleet(const FleetOptions& fleet,
                                       const BlockageOptions& options = {});

// ---------- field dose: the boom-total L/ha over a field run, what rate controllers are judged on
// Each machine is calibrated as made at the daemon's operating point ([pressure] set-point,
// [pwm] frequency), changed (the drawn change: wear, ageing, blockage, meter drift, supply
// ramp), then sprays a field (sim::FieldDutyProcess seeded per machine: correlated patches
// shared across the boom, closures, headlands, ground speed +-speed_swing) for run_s with the
// daemon's rate law: every request_period_s each nozzle is asked for its share of its
// calibrated full-open flow times the ground speed factor (the volume per area is kept; the
// daemon's rate law, speed_target.hpp, clipped at the full-open flow), the
// duties in the daemon's band (duty_min/duty_max, low-duty policy) and the online trim on or
// off. The field's ground speed replaces the drawn change's speed ramp.
//   target L/ha:  the requested flow integrated over time / the area sprayed (ground speed x
//                 nozzle width x time with the nozzle asked to spray), summed over the boom;
//   applied L/ha: the plant's TRUE delivered volume over the same area.
// The band moves some requests by policy, not by error: a request under the line's flow at
// duty_min is raised to it (raise_to_min), one over the line's flow at duty_max is held open.
// The law's volume is what the band decided (those requests replaced by the line's flow at
// duty_min / the held-open flow); the error against it is the controller's alone.
// The field this experiment sprays by default: sim::FieldDutyOptions with the shares kept
// inside the valves' band (field_dose_experiment.cpp says why).
sim::FieldDutyOptions field_dose_default_field();
// The daemon's spray law from its default configuration (daemon::spray_law_config).
SprayLawConfig field_dose_daemon_law();
struct FieldDoseOptions {
  double pressure_mpa = 0.4;  // the daemon's [pressure] setpoint_mpa
  double frequency_hz = 5.0;  // the daemon's [pwm] frequency_hz
  double run_s = 600.0;
  double request_period_s = 0.25;
  double settle_s = 3.0;  // pressure start-up with the boom closed, before the field
  sim::FieldDutyOptions field = field_dose_default_field();
  SprayLawConfig law = field_dose_daemon_law();
};
struct FieldDoseRun {
  double area_ha = 0.0;
  double target_l = 0.0;     // requested
  double law_l = 0.0;        // what the band decided
  double delivered_l = 0.0;  // TRUE
  double target_l_per_ha = 0.0;
  double applied_l_per_ha = 0.0;
  double error_pct = 0.0;      // (delivered - target) / target x 100
  double law_error_pct = 0.0;  // (delivered - law) / law x 100
  // Of the nozzle-time asked to spray: raised to duty_min, held open above duty_max [%].
  double raised_share_pct = 0.0;
  double held_open_share_pct = 0.0;
  // The band as shares of the held-open flow on this machine's calibrated lines: the largest
  // nozzle's line flow at duty_min, the smallest one's at duty_max.
  double band_low_share = 0.0;
  double band_high_share = 0.0;
  // The speed-following target above the full-open flows, % of the law's volume (not asked).
  double clipped_pct = 0.0;
};
struct FieldDoseMachine {
  FieldDoseRun trim_on, trim_off;
  MachineChange change{};
};
struct FieldDoseRow {
  Spread error_pct;  // signed; worst = the largest in size, with its sign
  Spread abs_error_pct;
  Spread law_error_pct;  // signed, as error_pct
  Spread raised_share_pct;
  Spread held_open_share_pct;
  Spread applied_l_per_ha;
  Spread clipped_pct;
};
struct FieldDoseFleetResult {
  FieldDoseRow trim_on, trim_off;
  std::vector<FieldDoseMachine> machines;
};
// One machine, one field (field_seed), one trim setting.
FieldDoseRun run_field_dose(const Machine& machine, const MachineChange& change,
                            std::uint64_t field_seed, bool trim, const FieldDoseOptions& options);
// Every machine with the trim on and off on the same field; fleet.changed = false: as made.
FieldDoseFleetResult run_field_dose_fleet(const FleetOptions& fleet,
                                          const FieldDoseOptions& options = {});

// Calibration runs are deterministic for given options, so the spray experiments share one
// per process (several tests of one binary, or both savings runs, calibrate once).
const CalibrationResult& cached_calibration(const CalibrationOptions& options);

// A machine calibrated as made at a set-point and PWM frequency (cached_calibration): the rig's
// configuration for it (set-point, frequency, the calibrated meter K-factor, no trace; the
// other settings the rig's defaults), its fitted lines and held-open flows.
struct CalibratedMachine {
  RigConfig config;
  std::vector<NozzleLine> lines;
  std::vector<double> full_flows;  // calibrated_full_flows()
};
CalibratedMachine calibrate_as_made(std::uint64_t seed, const plant::PlantParams& plant,
                                    double pressure_mpa, double frequency_hz);
// A rig on m.config with its lines and held-open flows set.
ClosedLoopRig calibrated_rig(const CalibratedMachine& m);

}  // namespace weedspray::lab::experiments
