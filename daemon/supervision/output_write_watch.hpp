// SPDX-License-Identifier: Apache-2.0
// Turns the outputs' write-failure counters into the `output_write_failed` alarm's condition and
// a message naming each failing output. The counters come from the threads that write (valve
// PWM, pressure loop, analog I/O worker) and from the main thread's own writes (buzzer, LED,
// safe writes); this class only compares them with what it saw last time.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace weedspray::daemon {

enum class OutputRole : std::uint8_t { kValves, kPump, kReturnValve, kHeartbeat, kBuzzer, kLed };
inline constexpr std::size_t kOutputRoleCount = 6;
const char* output_role_name(OutputRole role) noexcept;  // "valves", "pump relay", ...

struct OutputWriteCounters {
  // Failed writes per output since start (monotonic) that are faults...
  std::array<std::uint64_t, kOutputRoleCount> failed_writes{};
  // ...and those tolerated as superseded by the next write ([dac] write_failures_tolerated).
  std::array<std::uint64_t, kOutputRoleCount> tolerated_failures{};
  // Last errno of a safe write that still fails (0: the output is safe or was never forced).
  std::array<int, kOutputRoleCount> unsafe_error{};
};

class OutputWriteWatch {
 public:
  // `devices[i]`: what output i drives ("gpiochip1 line 7 (pump)"), for the message.
  explicit OutputWriteWatch(std::array<std::string, kOutputRoleCount> devices)
      : devices_(std::move(devices)) {}

  // Returns "" when no output failed since the last call and no safe write is failing, else
  // one clause per failing output: "pump relay (gpiochip1 line 7 (pump)): 3 failed writes;
  // safe value not written: Input/output error".
  std::string update(const OutputWriteCounters& now);

 private:
  std::array<std::string, kOutputRoleCount> devices_;
  OutputWriteCounters seen_{};
};

}  // namespace weedspray::daemon
