// Line-pressure ripple with 4 nozzles at 50 % duty: synchronous vs staggered PWM (UGV Fig. 8).
#include <vector>

#include "control/experiments/experiments.hpp"

namespace weedspray::control::experiments {
namespace {

RippleRun ripple_once(const RippleOptions& options, bool staggered) {
  RigConfig config;
  config.seed = options.seed;
  config.pwm_frequency_hz = options.frequency_hz;
  config.fixes = {staggered, false, false};
  config.record_period_s = 0.001;
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
  std::vector<double> p;
  p.reserve(run.trace.size());
  for (const auto& s : run.trace) p.push_back(s.pressure_mpa);
  run.pp_mpa = peak_to_peak(p);
  return run;
}

}  // namespace

RippleResult run_ripple(const RippleOptions& options) {
  return {ripple_once(options, false), ripple_once(options, true)};
}

}  // namespace weedspray::control::experiments
