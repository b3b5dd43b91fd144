// SPDX-License-Identifier: Apache-2.0
#include "io/sim/memory_output_bank.hpp"

#include <mutex>
#include <stdexcept>
#include <string>

namespace weedspray::io::sim {

MemoryOutputBank::MemoryOutputBank(std::size_t lines, std::uint32_t safe_mask, const Clock& clock,
                                   std::size_t history_capacity)
    : lines_(lines), safe_mask_(safe_mask), clock_(clock), mask_(safe_mask) {
  if (lines == 0 || lines > 32)
    throw std::invalid_argument("MemoryOutputBank: lines must be 1..32, got " +
                                std::to_string(lines));
  history_.reserve(history_capacity);
}

int MemoryOutputBank::write(std::uint32_t mask) noexcept {
  const std::uint32_t used = lines_ == 32 ? ~0U : ((1U << lines_) - 1U);
  std::lock_guard lock(mutex_);
  if (fail_error_ != 0) return -fail_error_;
  mask_ = mask & used;
  ++writes_;
  if (history_.size() < history_.capacity()) history_.push_back({clock_.now(), mask_});
  return 0;
}

int MemoryOutputBank::force_safe() noexcept {
  std::lock_guard lock(mutex_);
  ++force_safe_count_;
  if (fail_error_ != 0) return -fail_error_;
  mask_ = safe_mask_;
  return 0;
}

void MemoryOutputBank::fail_writes(int error) noexcept {
  std::lock_guard lock(mutex_);
  fail_error_ = error;
}

std::uint32_t MemoryOutputBank::mask() const noexcept {
  std::lock_guard lock(mutex_);
  return mask_;
}

std::uint64_t MemoryOutputBank::force_safe_count() const noexcept {
  std::lock_guard lock(mutex_);
  return force_safe_count_;
}

std::vector<OutputWrite> MemoryOutputBank::history() const {
  std::lock_guard lock(mutex_);
  return history_;
}

std::uint64_t MemoryOutputBank::write_count() const noexcept {
  std::lock_guard lock(mutex_);
  return writes_;
}

}  // namespace weedspray::io::sim
