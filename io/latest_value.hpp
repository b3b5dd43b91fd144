// SPDX-License-Identifier: Apache-2.0
// A latest-value slot: one writer publishes, any number of readers take the newest complete
// value without locks. Hand-written because the RT path needs it allocation- and lock-free.
//
// A seqlock whose payload is stored as relaxed atomic words, so concurrent reads are not data
// races. A reader that keeps colliding with the writer gives up after a bounded number of tries
// (try_read() returns false) instead of spinning forever when a SCHED_FIFO reader preempts the
// writer on the same core; the caller keeps its previous value and counts the miss.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace weedspray::io {

// What most slots carry: the value, when it was sampled, and the producer's error count.
template <class T>
struct Stamped {
  T value{};
  std::chrono::nanoseconds sample_time{};
  std::uint64_t error_count = 0;
};

template <class T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>, "LatestValue needs a trivially copyable T");

 public:
  static constexpr int kMaxReadAttempts = 64;

  LatestValue() noexcept {
    publish(T{});
    version_.store(0, std::memory_order_relaxed);
  }
  explicit LatestValue(const T& initial) noexcept { publish(initial); }

  // Single writer. Wait-free.
  void publish(const T& value) noexcept {
    std::array<std::uint64_t, kWords> words{};
    std::memcpy(words.data(), &value, sizeof(T));
    const std::uint64_t seq = sequence_.load(std::memory_order_relaxed);
    sequence_.store(seq + 1, std::memory_order_relaxed);  // odd: write in progress
    std::atomic_thread_fence(std::memory_order_release);
    for (std::size_t i = 0; i < kWords; ++i) payload_[i].store(words[i], std::memory_order_relaxed);
    sequence_.store(seq + 2, std::memory_order_release);
    version_.fetch_add(1, std::memory_order_release);
  }

  // Lock-free; bounded. Returns false (leaving `out` untouched) if no consistent copy was
  // obtained in kMaxReadAttempts tries.
  bool try_read(T& out) const noexcept {
    for (int attempt = 0; attempt < kMaxReadAttempts; ++attempt) {
      const std::uint64_t before = sequence_.load(std::memory_order_acquire);
      if (before & 1U) continue;
      std::array<std::uint64_t, kWords> words;
      for (std::size_t i = 0; i < kWords; ++i)
        words[i] = payload_[i].load(std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (sequence_.load(std::memory_order_relaxed) == before) {
        std::memcpy(static_cast<void*>(&out), words.data(), sizeof(T));
        return true;
      }
    }
    return false;
  }

  // Convenience for non-RT readers: retries until it succeeds.
  T read() const noexcept {
    T out{};
    while (!try_read(out)) {
    }
    return out;
  }

  // Number of publish() calls so far; a reader compares it to see whether anything is new.
  std::uint64_t version() const noexcept { return version_.load(std::memory_order_acquire); }

 private:
  static constexpr std::size_t kWords =
      (sizeof(T) + sizeof(std::uint64_t) - 1) / sizeof(std::uint64_t);
  std::atomic<std::uint64_t> sequence_{0};
  std::atomic<std::uint64_t> version_{0};
  std::array<std::atomic<std::uint64_t>, kWords> payload_{};
};

}  // namespace weedspray::io
