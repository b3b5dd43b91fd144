// SPDX-License-Identifier: Apache-2.0
// control::NozzleRecheck driven around the closed-loop rig from outside, as the daemon's control
// loop drives it: the rig runs in short slices, the re-check is stepped between them with the
// meter's count and the measured pressure, its duties are commanded while it holds a nozzle open
// (every other valve closed) and the caller's requests are put back the moment it lets go; each
// reading rescales that nozzle's line (scaled_line of the CALIBRATED line, the re-check reading
// against the calibration, never against its own rescale).
#pragma once

#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

#include "control/nozzle_recheck.hpp"
#include "control/spray_rate_law.hpp"
#include "lab/experiments/closed_loop_rig.hpp"

namespace weedspray::lab::experiments {

struct RigRecheckSettings {
  control::NozzleRecheckConfig config{};  // its `nozzles` is set from the lines
  double setpoint_mpa = 0.2;
  double pressure_tolerance_mpa = 0.02;  // read only with the measured pressure this close
  double slice_s = 0.01;                 // the rig runs this long between two steps
};

class RigRecheck {
 public:
  // `lines`, `full`: each nozzle's calibrated line and full-open flow [L/min].
  RigRecheck(const RigRecheckSettings& settings, std::span<const control::NozzleLine> lines,
             std::span<const double> full, double pulses_per_litre);

  // Runs the rig `seconds`; window(now, next) says whether the boom may be re-checked over the
  // slice [now, next]. `respray` asks for the caller's flows again when the override ends.
  template <typename Window, typename Respray>
  void run(ClosedLoopRig& rig, double seconds, Window&& window, Respray&& respray) {
    const double end = rig.time_s() + seconds;
    while (rig.time_s() < end - 1e-9) {
      const double now = rig.time_s();
      const double slice = std::min(settings_.slice_s, end - now);
      control::RecheckInput in;
      in.now_s = now;
      in.window = window(now, now + slice);
      in.pressure_ok = std::abs(rig.measured_pressure_mpa() - settings_.setpoint_mpa) <=
                       settings_.pressure_tolerance_mpa;
      in.meter_pulses = rig.plant().flow_meter_pulses();
      in.pulses_per_litre = pulses_per_litre_;
      in.pressure_mpa = rig.measured_pressure_mpa();
      const bool was_overriding = recheck_.overriding();
      const int was_nozzle = recheck_.current_nozzle();
      recheck_.step(in, lines_);
      if (recheck_.overriding()) {
        if (!was_overriding || recheck_.current_nozzle() != was_nozzle) {
          rescale(rig);
          rig.command_duties(recheck_.duties());
        }
      } else if (was_overriding) {
        rescale(rig);
        respray();
      }
      rig.run_for(slice);
    }
  }

  // A whole-boom re-check with the window open throughout (a headland long enough for every
  // nozzle), `respray` called as it ends; at most `limit_s` (a pressure that never settles).
  template <typename Respray>
  void run_whole_boom(ClosedLoopRig& rig, double limit_s, Respray&& respray) {
    const std::size_t done = recheck_.completed();
    const double end = rig.time_s() + limit_s;
    while (recheck_.completed() == done && rig.time_s() < end - 1e-9)
      run(
          rig, settings_.slice_s, [](double, double) { return true; }, respray);
  }

  const control::NozzleRecheck& recheck() const { return recheck_; }
  bool overriding() const { return recheck_.overriding(); }

 private:
  // Each nozzle's calibrated line and full-open flow times its last reading.
  void rescale(ClosedLoopRig& rig) const;

  RigRecheckSettings settings_;
  control::NozzleRecheck recheck_;
  std::vector<control::NozzleLine> lines_;  // as calibrated: the re-check reads against these
  std::vector<double> full_;
  double pulses_per_litre_;
};

}  // namespace weedspray::lab::experiments
