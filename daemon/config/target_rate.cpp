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

std::string apply_target_rate_l_per_ha(Config& config) {
  auto& spray = config.spray;
  if (spray.target_rate_l_per_ha <= 0) return {};
  const double flow_l_per_min = nozzle_flow_for_rate(
      spray.target_rate_l_per_ha, config.boom.nozzle_width_m, spray.nominal_speed_m_per_s);
  // Both set agree when the file is --dump-config's output; otherwise the user meant one.
  if (config.sources.contains("spray.nominal_flow_l_per_min") &&
      std::abs(spray.nominal_flow_l_per_min - flow_l_per_min) > 1e-6 * flow_l_per_min) {
    std::ostringstream message;
    message << "gives " << flow_l_per_min << " L/min per nozzle but spray.nominal_flow_l_per_min"
            << " is set to " << spray.nominal_flow_l_per_min
            << ": set the dose by one of the two keys";
    return message.str();
  }
  for (const auto& spec : config_keys()) {
    if (spec.full_name() != "spray.nominal_flow_l_per_min") continue;
    if (flow_l_per_min < spec.min || flow_l_per_min > spec.max) {
      std::ostringstream message;
      message << spray.target_rate_l_per_ha << " L/ha at " << spray.nominal_speed_m_per_s
              << " m/s over boom.nozzle_width_m = " << config.boom.nozzle_width_m << " m needs "
              << flow_l_per_min << " L/min per nozzle, outside the nozzles' " << spec.min << ".."
              << spec.max << " L/min";
      return message.str();
    }
  }
  spray.nominal_flow_l_per_min = flow_l_per_min;
  return {};
}

}  // namespace weedspray::daemon
