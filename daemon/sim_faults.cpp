#include "daemon/sim_faults.hpp"

#include <cstdlib>

#include "control/plant/hydraulic_plant.hpp"

namespace weedspray::daemon {

std::optional<SimFault> parse_sim_fault(const std::string& text) {
  const auto at = text.find('@');
  if (at == std::string::npos) return std::nullopt;
  SimFault fault;
  fault.name = text.substr(0, at);
  const std::string time = text.substr(at + 1);
  char* end = nullptr;
  fault.at_s = std::strtod(time.c_str(), &end);
  if (time.empty() || *end != '\0' || !(fault.at_s >= 0)) return std::nullopt;
  using Plant = control::plant::HydraulicPlant;
  if (fault.name == "sensor_open") {
    fault.apply = [](Plant& p) { p.set_sensor_wire_broken(true); };
  } else if (fault.name == "sensor_short") {
    fault.apply = [](Plant& p) { p.set_sensor_shorted(true); };
  } else if (fault.name == "filter_blocked") {
    fault.apply = [](Plant& p) { p.set_filter_blockage(1.0); };
  } else if (fault.name == "tank_empty") {
    fault.apply = [](Plant& p) { p.set_tank_level_l(0.0); };
  } else if (fault.name.size() == 14 && fault.name.starts_with("nozzle") &&
             fault.name.ends_with("_blocked") && fault.name[6] >= '0' && fault.name[6] <= '7') {
    const int nozzle = fault.name[6] - '0';
    fault.apply = [nozzle](Plant& p) {
      if (nozzle < p.nozzle_count()) p.set_nozzle_blockage(nozzle, 1.0);
    };
  } else {
    return std::nullopt;
  }
  return fault;
}

}  // namespace weedspray::daemon
