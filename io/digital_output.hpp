// SPDX-License-Identifier: Apache-2.0
// A bank of digital outputs switched together: the nozzle valves, the pump relay, buzzer/LED.
// Bit i of a mask is line i in LOGICAL terms (1 = energised/on); active-low wiring is the
// backend's business.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "io/emergency_outputs.hpp"

namespace weedspray::io {

class DigitalOutputBank {
 public:
  virtual ~DigitalOutputBank() = default;
  // Number of lines (at most 32).
  virtual std::size_t size() const noexcept = 0;
  // Sets every line of the bank at one instant (one driver call). Returns 0 or -errno.
  virtual int write(std::uint32_t mask) noexcept = 0;
  // Drives every line to its declared safe value. Called explicitly on every exit and fault
  // path: the kernel does not promise what a released line does. The backend retries a failed
  // write itself; returns 0, or -errno when the lines could still not be written (the caller
  // raises an alarm naming the output and tries again).
  virtual int force_safe() noexcept = 0;
  // What the bank drives, for alarms and logs ("gpiochip1 lines 3,4 (valve0,valve1)").
  virtual std::string describe() const { return {}; }
  // The logical mask force_safe() writes.
  virtual std::uint32_t safe_mask() const noexcept = 0;
  // The one syscall that writes the safe values on a descriptor held open, for the fatal-exit
  // handlers (io/emergency_outputs.hpp). False when the backend has none (simulation).
  virtual bool emergency_write(EmergencyWrite& /*out*/) const noexcept { return false; }
};

}  // namespace weedspray::io
