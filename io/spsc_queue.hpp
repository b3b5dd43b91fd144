// SPDX-License-Identifier: Apache-2.0
// Bounded single-producer single-consumer queue for commands into RT loops (e.g. D-Bus -> RT).
// Hand-written because the RT side needs it allocation-free and wait-free; the storage is a
// fixed array sized at compile time.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <optional>
#include <type_traits>

namespace weedspray::io {

template <class T, std::size_t Capacity>
class SpscQueue {
  static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0, "Capacity: a power of two");
  static_assert(std::is_nothrow_copy_assignable_v<T> || std::is_nothrow_move_assignable_v<T>);

 public:
  // Producer side. Returns false when full (the item is not queued).
  bool try_push(T item) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_cache_ == Capacity) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail - head_cache_ == Capacity) return false;
    }
    slots_[tail & (Capacity - 1)] = std::move(item);
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  // Consumer side. Returns std::nullopt when empty.
  std::optional<T> try_pop() noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_cache_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head == tail_cache_) return std::nullopt;
    }
    std::optional<T> item{std::move(slots_[head & (Capacity - 1)])};
    head_.store(head + 1, std::memory_order_release);
    return item;
  }

  // Approximate when called concurrently.
  std::size_t size() const noexcept {
    return tail_.load(std::memory_order_acquire) - head_.load(std::memory_order_acquire);
  }
  static constexpr std::size_t capacity() noexcept { return Capacity; }

 private:
  static constexpr std::size_t kLine = 64;  // keep producer and consumer indices apart
  alignas(kLine) std::atomic<std::size_t> head_{0};
  alignas(kLine) std::size_t tail_cache_ = 0;  // consumer's copy of tail_
  alignas(kLine) std::atomic<std::size_t> tail_{0};
  alignas(kLine) std::size_t head_cache_ = 0;  // producer's copy of head_
  std::array<T, Capacity> slots_{};
};

}  // namespace weedspray::io
