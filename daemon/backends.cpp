#include "daemon/backends.hpp"

namespace weedspray::daemon {

void Backends::force_safe() noexcept {
  if (valves != nullptr) valves->force_safe();
  if (pump != nullptr) pump->force_safe();
  if (return_valve != nullptr) return_valve->force_safe();
  if (buzzer != nullptr) buzzer->force_safe();
  if (led != nullptr) led->force_safe();
}

}  // namespace weedspray::daemon
