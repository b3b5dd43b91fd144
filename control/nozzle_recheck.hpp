// SPDX-License-Identifier: Apache-2.0
// Headland re-check of each nozzle against its calibration, from the ONE line flow meter.
//
// While spraying, the meter sees the sum of every open nozzle, and a judge that learns its
// baseline in the job (nozzle_health.hpp) cannot see a nozzle that was already off when the job
// started, nor separate the nozzles on a field's correlated, often closed duties. Off crop (the
// headland, a turn, a stop, the start of a job) the boom sprays nothing, so each nozzle can be
// held open alone and read against the meter, as `calibrate nozzles` does:
//   settle_s    nozzle i alone held open (duty 100, the others 0), not read: the valve opens,
//               the line refills and the pressure loop recovers from the dip one nozzle alone
//               causes (settle time counts only while the caller says the pressure is fine);
//   measure_s   metered litres L = pulses / (pulses per litre) against the calibrated promise
//               E = integral of held_open_flow_l_per_min(line_i, P(t)) dt over the same time,
//               ratio_i = L / E. Integrating the promise at the pressure of each call (not one
//               pressure at the end) takes the pressure's wobble out of the ratio: flow goes
//               with sqrt(P) in the promise as in the nozzle.
// The ratio is against the CALIBRATION, never against the job: a nozzle blocked before the job
// is found at the first re-check.
//
// Judging (decision limits). A nozzle is named in alarm once |ratio - 1| reaches
// alarm_fraction - tolerance, in warning once it reaches warn_fraction - tolerance. The
// tolerance (default 0.015) is the reading's own uncertainty (meter pulses +-1 at each end of
// a ~180-pulse reading: 0.65 L/min for 2 s at 8500 pulses/L, up to +-1.1 %; the meter's
// low-flow drag; the pressure sensor's noise): a nozzle truly
// 10 % off reads 10 % +- that, and must be named, not one in two; a healthy nozzle must stray
// by alarm_fraction - tolerance (8.5 %, several times the reading's scatter) to be named.
// Each nozzle's verdict holds until its next reading (a cleared nozzle clears its alarm).
//
// Rescaling: scale(i) is nozzle i's last ratio (1 until read), clamped to [min_scale,
// max_scale]; the caller applies it to the line (scaled_line: slope, intercept and full-open
// flow x scale) so the rate law asks that nozzle for the duty that gives the requested flow.
// Pass the CALIBRATED lines to step() (not the scaled ones): the ratio stays against the
// calibration.
//
// Windows and cadence. The caller says whether the boom may be re-checked now (`window`: off
// crop, pump on, nothing to spray). A whole-boom re-check starts at a window at most every
// interval_s (from the start of the previous one); the first window after construction or
// reset() always starts one (the start of a job). While a re-check is under way and the window
// is open, overriding() is true and duties() are the valves' duties. When the window closes
// (crop again) the override ends on that very call and the nozzle being read is abandoned; the
// next window resumes at that nozzle (its settle again), whatever the interval.
//
// Pure (no clocks, threads, I/O or exceptions in step()), fixed-size state, fixed cost per call
// (a loop over the nozzles only when a reading completes): callable from a 500 Hz control loop.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "control/spray_rate_law.hpp"

namespace weedspray::control {

// The valve driver's limit (io::kMaxValves): one slot per valve.
inline constexpr std::size_t kMaxRecheckNozzles = 32;

struct NozzleRecheckConfig {
  std::size_t nozzles = 4;
  double settle_s = 1.0;     // each nozzle held open, not read (valve, line, pressure loop)
  double measure_s = 2.0;    // then read against the meter
  double interval_s = 60.0;  // a whole-boom re-check at most this often (0: every window)
  double warn_fraction = 0.05;
  double alarm_fraction = 0.10;
  double tolerance = 0.015;  // the reading's uncertainty taken off both limits (see above)
  double min_scale = 0.5;    // the scale applied to a line is clamped to [min, max]
  double max_scale = 1.5;
};

// Throws std::invalid_argument naming the field.
void validate(const NozzleRecheckConfig& config);

// One control tick's inputs.
struct RecheckInput {
  double now_s = 0.0;  // monotonic seconds (any origin; not before the last call)
  // The boom may be re-checked now: off crop (headland, turn, stopped), pump on, nothing to
  // spray. Closing it ends the override on this call.
  bool window = false;
  // The line pressure is fresh and near its set-point: the settle counts only while it is, and
  // a reading is restarted (settle again) when it is not. Does not end the override.
  bool pressure_ok = false;
  std::uint64_t meter_pulses = 0;  // the meter's running count
  double pulses_per_litre = 0.0;
  double pressure_mpa = 0.0;  // line pressure now
};

// `line` with slope, intercept and full-open flow x scale (what a nozzle reading `scale` of its
// calibration gives at every duty).
NozzleLine scaled_line(const NozzleLine& line, double scale) noexcept;

class NozzleRecheck {
 public:
  // Throws std::invalid_argument (validate).
  explicit NozzleRecheck(const NozzleRecheckConfig& config);

  // One call per control tick. `lines`: each nozzle's calibrated line (at least `nozzles`; a
  // line without a full-open flow is read against the line at 100 %).
  void step(const RecheckInput& in, std::span<const NozzleLine> lines) noexcept;

  // The re-check holds the valves now: apply duties() instead of the rate law's.
  bool overriding() const noexcept { return overriding_; }
  // Each nozzle's duty while overriding() [%]: 100 for the nozzle being read, 0 for the rest.
  std::span<const double> duties() const noexcept { return {duties_.data(), config_.nozzles}; }
  // Whether a whole-boom re-check is under way (started, not all nozzles read yet).
  bool in_progress() const noexcept { return in_progress_; }
  // The nozzle being read (or next to be read), -1 when no re-check is under way.
  int current_nozzle() const noexcept { return in_progress_ ? static_cast<int>(nozzle_) : -1; }

  // Nozzle i's last metered / calibrated ratio, 1 until read.
  double ratio(std::size_t nozzle) const noexcept;
  // When it was read (now_s of the call that completed it); < 0 until read.
  double measured_at_s(std::size_t nozzle) const noexcept;
  // The factor to apply to nozzle i's line (scaled_line): its ratio, clamped.
  double scale(std::size_t nozzle) const noexcept;
  // The nozzle furthest off among those past the warning / alarm limit, or -1.
  int warned_nozzle() const noexcept { return warned_; }
  int alarmed_nozzle() const noexcept { return alarmed_; }
  // Whole-boom re-checks completed since construction / reset().
  std::size_t completed() const noexcept { return completed_; }

  // Forget every reading; the next window starts a re-check (a new job).
  void reset() noexcept;

  const NozzleRecheckConfig& config() const noexcept { return config_; }

 private:
  using Vector = std::array<double, kMaxRecheckNozzles>;
  void start_nozzle(const RecheckInput& in) noexcept;
  void finish_nozzle(const RecheckInput& in) noexcept;
  void judge() noexcept;

  NozzleRecheckConfig config_;
  Vector duties_{};
  Vector ratio_{};
  Vector measured_at_s_{};
  bool in_progress_ = false;
  bool ever_started_ = false;
  bool overriding_ = false;
  bool measuring_ = false;
  std::size_t nozzle_ = 0;
  double started_s_ = 0.0;   // the last whole-boom re-check's start
  double last_now_s_ = 0.0;  // the previous call's time (each call's dt)
  bool has_last_ = false;
  double phase_s_ = 0.0;            // settled / measured so far in this nozzle's phase
  std::uint64_t phase_pulses_ = 0;  // the meter's count when measuring began
  double promised_l_ = 0.0;         // the calibrated promise over the measuring so far
  int warned_ = -1;
  int alarmed_ = -1;
  std::size_t completed_ = 0;
};

}  // namespace weedspray::control
