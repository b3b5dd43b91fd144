// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/target_rate.hpp"

#include <cmath>
#include <sstream>

#include "daemon/config/config_schema.hpp"

namespace weedspray::daemon {

double nozzle_flow_for_rate(double rate_l_per_ha, double width_m, double speed_m_per_s) noexcept {
  return rate_l_per_ha / 10000.0 * 60.0 * width_m * speed_m_per_s;
}

double rate_for_nozzle_flow(double flow_l_per_min, double width_m, double speed_m_per_s) noexcept {
  return flow_l_per_min * 10000.0 / (60.0 * width_m * speed_m_per_s);
}

RateFlow flow_for_target_rate(const Config& config, double rate_l_per_ha) {
  RateFlow result;
  result.flow_l_per_min = nozzle_flow_for_rate(rate_l_per_ha, config.boom.nozzle_width_m,
                                               config.spray.nominal_speed_m_per_s);
  const auto& spec = config_key("spray.nominal_flow_l_per_min");
  // Negated, so that a NaN is refused too.
  if (!(result.flow_l_per_min >= spec.min && result.flow_l_per_min <= spec.max)) {
    std::ostringstream message;
    message << rate_l_per_ha << " L/ha at " << config.spray.nominal_speed_m_per_s
            << " m/s over boom.nozzle_width_m = " << config.boom.nozzle_width_m << " m needs "
            << result.flow_l_per_min << " L/min per nozzle, outside the nozzles' " << spec.min
            << ".." << spec.max << " L/min";
    result.refusal = message.str();
  }
  return result;
}

std::string apply_target_rate_l_per_ha(Config& config) {
  auto& spray = config.spray;
  if (spray.target_rate_l_per_ha <= 0) return {};
  const RateFlow rate = flow_for_target_rate(config, spray.target_rate_l_per_ha);
  // Both set agree when the file is --dump-config's output; otherwise the user meant one.
  if (config.sources.contains("spray.nominal_flow_l_per_min") &&
      std::abs(spray.nominal_flow_l_per_min - rate.flow_l_per_min) > 1e-6 * rate.flow_l_per_min) {
    std::ostringstream message;
    message << "gives " << rate.flow_l_per_min
            << " L/min per nozzle but spray.nominal_flow_l_per_min is set to "
            << spray.nominal_flow_l_per_min << ": set the dose by one of the two keys";
    return message.str();
  }
  if (!rate.refusal.empty()) return rate.refusal;
  spray.nominal_flow_l_per_min = rate.flow_l_per_min;
  return {};
}

}  // namespace weedspray::daemon
