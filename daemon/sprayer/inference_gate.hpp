// SPDX-License-Identifier: Apache-2.0
// One weed-model inference at a time across the camera workers, served in the order the
// workers asked (a ticket lock): a camera whose worker asks again at once cannot overtake one
// that is already waiting, so no camera starves the others.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace weedspray::daemon {

class InferenceGate {
 public:
  // Held while its owner runs an inference; released when destroyed.
  class Turn {
   public:
    explicit Turn(InferenceGate* gate) : gate_(gate) {}
    Turn(Turn&& other) noexcept : gate_(other.gate_) { other.gate_ = nullptr; }
    Turn& operator=(Turn&&) = delete;
    Turn(const Turn&) = delete;
    ~Turn() {
      if (gate_ != nullptr) gate_->release();
    }

   private:
    InferenceGate* gate_;
  };

  // Blocks until every caller that asked earlier has had its turn.
  [[nodiscard]] Turn acquire();
  // Callers blocked in acquire() now.
  [[nodiscard]] std::uint64_t waiting() const;

 private:
  void release();

  mutable std::mutex mutex_;
  std::condition_variable next_served_;
  std::uint64_t next_ticket_ = 0;
  std::uint64_t serving_ = 0;
  bool held_ = false;
};

}  // namespace weedspray::daemon
