// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/output_write_watch.hpp"

#include <cstring>

namespace weedspray::daemon {

const char* output_role_name(OutputRole role) noexcept {
  switch (role) {
    case OutputRole::kValves:
      return "valves";
    case OutputRole::kPump:
      return "pump relay";
    case OutputRole::kReturnValve:
      return "return valve DAC";
    case OutputRole::kHeartbeat:
      return "heartbeat";
    case OutputRole::kBuzzer:
      return "buzzer";
    case OutputRole::kLed:
      return "alarm LED";
  }
  return "?";
}

std::string OutputWriteWatch::update(const OutputWriteCounters& now) {
  std::string message;
  for (std::size_t i = 0; i < kOutputRoleCount; ++i) {
    const std::uint64_t failed = now.failed_writes[i] - seen_.failed_writes[i];
    const int unsafe = now.unsafe_error[i];
    if (failed == 0 && unsafe == 0) continue;
    // append() only: GCC 12's -Wrestrict misfires on chains of operator+ here.
    if (!message.empty()) message.append("; ");
    message.append(output_role_name(static_cast<OutputRole>(i)));
    if (!devices_[i].empty()) message.append(" (").append(devices_[i]).append(")");
    message.append(":");
    if (failed > 0) message.append(" ").append(std::to_string(failed)).append(" failed write(s)");
    if (unsafe != 0) message.append(" safe value not written: ").append(std::strerror(unsafe));
  }
  seen_ = now;
  return message;
}

}  // namespace weedspray::daemon
