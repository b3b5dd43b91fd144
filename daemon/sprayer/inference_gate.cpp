// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/inference_gate.hpp"

namespace weedspray::daemon {

InferenceGate::Turn InferenceGate::acquire() {
  std::unique_lock lock(mutex_);
  const std::uint64_t ticket = next_ticket_++;
  next_served_.wait(lock, [&] { return serving_ == ticket; });
  held_ = true;
  return Turn(this);
}

void InferenceGate::release() {
  {
    std::lock_guard lock(mutex_);
    held_ = false;
    ++serving_;
  }
  next_served_.notify_all();
}

std::uint64_t InferenceGate::waiting() const {
  std::lock_guard lock(mutex_);
  return next_ticket_ - serving_ - (held_ ? 1 : 0);
}

}  // namespace weedspray::daemon
