// SPDX-License-Identifier: Apache-2.0
#include "lab/experiments/rig_recheck.hpp"

namespace weedspray::lab::experiments {
namespace {

control::NozzleRecheckConfig sized(control::NozzleRecheckConfig config, std::size_t nozzles) {
  config.nozzles = nozzles;
  return config;
}

}  // namespace

RigRecheck::RigRecheck(const RigRecheckSettings& settings,
                       std::span<const control::NozzleLine> lines, std::span<const double> full,
                       double pulses_per_litre)
    : settings_(settings),
      recheck_(sized(settings.config, lines.size())),
      lines_(lines.begin(), lines.end()),
      full_(full.begin(), full.end()),
      pulses_per_litre_(pulses_per_litre) {
  for (std::size_t i = 0; i < lines_.size() && i < full_.size(); ++i)
    lines_[i].full_open_flow_l_per_min = full_[i];
}

void RigRecheck::rescale(ClosedLoopRig& rig) const {
  std::vector<control::NozzleLine> scaled(lines_.size());
  std::vector<double> full(full_.size());
  for (std::size_t i = 0; i < lines_.size(); ++i) {
    const double scale = recheck_.scale(i);
    scaled[i] = control::scaled_line(lines_[i], scale);
    if (i < full.size()) full[i] = full_[i] * scale;
  }
  rig.set_nozzle_lines(scaled);
  rig.set_full_open_flows(full);
}

}  // namespace weedspray::lab::experiments
