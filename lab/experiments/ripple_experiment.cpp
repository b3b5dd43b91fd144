// SPDX-License-Identifier: Apache-2.0
// Line-pressure ripple with 4 nozzles at 50 % duty: synchronous vs staggered PWM (UGV Fig. 8).
#include <vector>

#include "lab/experiments/experiments.hpp"
#include "lab/experiments/vocabulary.hpp"

namespace weedspray::lab::experiments {
namespace {

RippleRun ripple_once(const RippleOptions& options, bool staggered) {
  RigConfig config;
  config.seed = options.seed;
  config.pwm_frequency_hz = options.frequency_hz;
  config.fixes = {staggered, false, false};
  config.record_period_s = 0.0005;  // the pump's pulsation is ~100 Hz
  config.plant = options.plant;
  ClosedLoopRig rig(config);
  const std::vector<double> duties(static_cast<std::size_t>(rig.plant().nozzle_count()),
                                   options.duty_pct);
  rig.command_duties(duties);
  rig.start();
  rig.run_for(options.settle_s);
  rig.clear_trace();
  rig.run_for(options.measure_s);
  RippleRun run;
  run.trace = rig.trace();
  std::vector<double> p, boom;
  p.reserve(run.trace.size());
  boom.reserve(run.trace.size());
  for (const auto& s : run.trace) {
    p.push_back(s.pressure_mpa);
    boom.push_back(s.boom_pressure_mpa);
  }
  run.pp_mpa = peak_to_peak(p);
  run.boom_pp_mpa = peak_to_peak(boom);
  return run;
}

}  // namespace

RippleResult run_ripple(const RippleOptions& options) {
  return {ripple_once(options, false), ripple_once(options, true)};
}

RippleFleetResult run_ripple_fleet(const FleetOptions& fleet, const RippleOptions& base) {
  std::vector<double> sync, stag, ratio, sync_boom, stag_boom;
  for (const Machine& m : draw_machines(fleet.seed, fleet.plants)) {
    RippleOptions options = base;
    options.seed = m.seed;
    options.plant = m.params;
    const RippleResult r = run_ripple(options);
    sync.push_back(r.synchronous.pp_mpa);
    stag.push_back(r.staggered.pp_mpa);
    ratio.push_back(r.staggered.pp_mpa > 0 ? r.synchronous.pp_mpa / r.staggered.pp_mpa : 0.0);
    sync_boom.push_back(r.synchronous.boom_pp_mpa);
    stag_boom.push_back(r.staggered.boom_pp_mpa);
  }
  // Worst ratio = the smallest advantage of staggering.
  return {spread_of(sync), spread_of(stag), spread_of(ratio, true), spread_of(sync_boom),
          spread_of(stag_boom)};
}

}  // namespace weedspray::lab::experiments
