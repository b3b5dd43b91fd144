// SPDX-License-Identifier: Apache-2.0
// spray.target_rate_l_per_ha: the dose as a sprayer's operator states it (L/ha), turned into
// the nozzle flow at the nominal speed that the rate law works in.
#pragma once

#include <string>

#include "daemon/config/config.hpp"

namespace weedspray::daemon {

// The nozzle flow that gives `rate_l_per_ha` at `speed_m_per_s` over `width_m`:
// q = R x 60 x w x v / 10000 (L/min).
double nozzle_flow_for_rate(double rate_l_per_ha, double width_m, double speed_m_per_s) noexcept;
// The rate that `flow_l_per_min` per nozzle gives at `speed_m_per_s` over `width_m` (L/ha).
double rate_for_nozzle_flow(double flow_l_per_min, double width_m, double speed_m_per_s) noexcept;

// The nozzle flow a dose of `rate_l_per_ha` needs at `config`'s nominal speed and nozzle width,
// or why it cannot be had: a flow outside the spray.nominal_flow_l_per_min key's range.
struct RateFlow {
  double flow_l_per_min = 0;
  std::string refusal;  // "" = within the nozzles' range
};
RateFlow flow_for_target_rate(const Config& config, double rate_l_per_ha);

// With spray.target_rate_l_per_ha > 0, sets spray.nominal_flow_l_per_min from it. Returns ""
// when done (or nothing to do), else why not: nominal_flow_l_per_min set in a file to another
// flow, or a flow outside that key's range.
std::string apply_target_rate_l_per_ha(Config& config);

}  // namespace weedspray::daemon
