// SPDX-License-Identifier: Apache-2.0
// A PulseInput on the kernel's Counter subsystem, for pulse rates up to tens of kHz without
// loss: the kernel counts every edge itself and this class only reads the running total.
//
// The intended driver is `interrupt-cnt` (device tree: compatible = "interrupt-counter"), whose
// hard interrupt handler does one atomic_inc per rising edge; nothing is queued, so nothing can
// overflow (overflow_count stays 0). Its total is read from
// /sys/bus/counter/devices/counterN/countM/count with pread on a file opened once, by a
// SCHED_FIFO thread (ThreadRole::kPulseInput) every poll_period, and published wait-free.
//
// last_edge_time is NOT a kernel edge timestamp: it is the CLOCK_MONOTONIC time of the poll at
// which the total was seen to change, so the latest edge lies in (previous poll, that time].
// Rate estimates from it are quantised to the poll period.
//
// The sysfs value is a u64, but interrupt-cnt keeps an int and sign-extends it (after 2^31
// pulses it jumps from 2147483647 to 18446744071562067968). Totals are therefore advanced by
// the change of the low 32 bits, exact for any counter at least 32 bits wide while a poll sees
// fewer than 2^31 new pulses. A change of 2^31 or more in those bits means the total went
// backwards (someone wrote `count`, or the device was reset): counted as an error, and the new
// value becomes the reference.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "io/pulse_input.hpp"
#include "io/realtime.hpp"

namespace weedspray::io::hw {

struct CounterPulseInputConfig {
  // "counter0", a full directory path, or the counter's `name` attribute (interrupt-cnt names
  // it after its device: on a Raspberry Pi the device-tree node name, e.g. "weedspray-flow").
  std::string device;
  int count_index = 0;  // countN under the counter directory
  // How often the total is read; also the resolution of last_edge_time.
  std::chrono::nanoseconds poll_period = std::chrono::milliseconds(2);
  // Root of the counter device tree (tests point it at a fake tree).
  std::string sysfs_root = "/sys/bus/counter/devices";
};

class CounterPulseInput final : public PulseInput {
 public:
  // Finds the counter, writes 1 to countN/enable if it reads 0 (interrupt-cnt keeps its
  // interrupt off until then), opens countN/count and starts the polling thread. Throws
  // std::runtime_error naming the path, the errno text and what to do about it.
  explicit CounterPulseInput(const CounterPulseInputConfig& config);
  ~CounterPulseInput() override;  // stops the thread; leaves the kernel counter enabled
  CounterPulseInput(const CounterPulseInput&) = delete;
  CounterPulseInput& operator=(const CounterPulseInput&) = delete;

  // count: pulses since construction. Wait-free.
  PulseSnapshot snapshot() const noexcept override;
  RtStatus thread_status() const noexcept;
  const std::string& count_path() const noexcept;  // the sysfs file being read

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Finds the counter directory for `device` (see CounterPulseInputConfig). Throws
// std::runtime_error.
std::string resolve_counter_device_dir(const std::string& device, const std::string& sysfs_root);

// Parses a sysfs unsigned decimal ("123\n"): digits and at most one trailing newline.
bool parse_counter_value(std::string_view text, std::uint64_t& value) noexcept;

// The pulses since start, advanced from successive raw kernel totals by the change of their low
// 32 bits (see the header comment). Separate from the thread so its arithmetic is testable.
class CounterTotal {
 public:
  enum class Change { kNone, kCounted, kWentBackwards };

  explicit CounterTotal(std::uint64_t first_raw) noexcept : reference_(first_raw) {}
  // kWentBackwards counts nothing and makes `raw` the new reference.
  Change update(std::uint64_t raw) noexcept;
  std::uint64_t count() const noexcept { return count_; }

 private:
  std::uint64_t reference_;
  std::uint64_t count_ = 0;
};

}  // namespace weedspray::io::hw
