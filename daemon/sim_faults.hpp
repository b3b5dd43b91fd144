// Faults injected into the simulated plant at a given time (weedsprayd --sim --sim-fault), so
// alarms and the fail-safe paths can be exercised end to end.
#pragma once

#include <functional>
#include <optional>
#include <string>

namespace weedspray::control::plant {
class HydraulicPlant;
}

namespace weedspray::daemon {

struct SimFault {
  std::string name;
  double at_s = 0;
  std::function<void(control::plant::HydraulicPlant&)> apply;
};

// "sensor_open@5" -> the fault; nullopt for an unknown name or a malformed time.
std::optional<SimFault> parse_sim_fault(const std::string& text);

}  // namespace weedspray::daemon
