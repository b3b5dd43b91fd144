// SPDX-License-Identifier: Apache-2.0
// An output bank that only remembers: the current mask, every write (time from the injected
// clock), and force_safe() calls. For tests and for outputs that have no plant counterpart
// (buzzer, LED). History is bounded by a capacity reserved at construction.
#pragma once

#include <chrono>
#include <cstdint>
#include <vector>

#include "io/clock.hpp"
#include "io/digital_output.hpp"
#include "io/sim/priority_inheriting_mutex.hpp"

namespace weedspray::io::sim {

struct OutputWrite {
  std::chrono::nanoseconds time{};
  std::uint32_t mask = 0;
};

class MemoryOutputBank final : public DigitalOutputBank {
 public:
  MemoryOutputBank(std::size_t lines, std::uint32_t safe_mask, const Clock& clock,
                   std::size_t history_capacity = 4096);

  std::size_t size() const noexcept override { return lines_; }
  int write(std::uint32_t mask) noexcept override;
  int force_safe() noexcept override;
  std::string describe() const override { return "memory bank"; }

  // Fault injection: every later write and force_safe() fails with -error (0 = works again);
  // a failed write leaves the lines as they were, as a refused ioctl does.
  void fail_writes(int error) noexcept;
  std::uint32_t safe_mask() const noexcept override { return safe_mask_; }

  std::uint32_t mask() const noexcept;
  std::uint64_t force_safe_count() const noexcept;
  // Writes beyond the history capacity are counted but not kept.
  std::vector<OutputWrite> history() const;
  std::uint64_t write_count() const noexcept;

 private:
  std::size_t lines_;
  std::uint32_t safe_mask_;
  const Clock& clock_;
  mutable PriorityInheritingMutex mutex_;  // sim only: tests read while the driver thread writes
  std::uint32_t mask_;
  std::uint64_t force_safe_count_ = 0;
  std::uint64_t writes_ = 0;
  int fail_error_ = 0;
  std::vector<OutputWrite> history_;
};

}  // namespace weedspray::io::sim
