// SPDX-License-Identifier: Apache-2.0
// How late a real-time loop wakes (or writes an edge) after its deadline, as a fixed-bucket
// histogram: p50/p99/max per loop for the timing report without storing samples.
// Hand-written because it is updated on the SCHED_FIFO threads: no allocation, no locks.
// One writer (the loop's own thread) and any number of readers; counts are relaxed atomics, so
// a reader sees a consistent-enough picture (a bucket may be one sample ahead of the total).
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace weedspray::io {

// Bucket upper edges: ten per decade (R10 series) from 1 us to 1 s, then one overflow bucket.
// A quantile is reported as the upper edge of the bucket it falls in (at most 26 % high).
class LatenessHistogram {
 public:
  static constexpr std::size_t kDecades = 6;  // 1 us .. 1 s
  static constexpr std::size_t kPerDecade = 10;
  static constexpr std::size_t kBuckets = kDecades * kPerDecade + 2;  // + "<= 0" + overflow

  // Upper edge of bucket i in nanoseconds; bucket 0 holds lateness <= 1 us, the last one
  // everything above 1 s (edge reported as the max seen).
  static constexpr std::int64_t upper_edge_ns(std::size_t i) noexcept {
    if (i == 0) return 1'000;
    if (i >= kBuckets - 1) return INT64_MAX;
    constexpr std::array<std::int64_t, kPerDecade> r10{1000, 1250, 1600, 2000, 2500,
                                                       3150, 4000, 5000, 6300, 8000};
    const std::size_t k = i - 1;  // 0-based over the R10 steps above 1 us
    std::int64_t decade = 1;
    for (std::size_t d = 0; d < (k + 1) / kPerDecade; ++d) decade *= 10;
    return r10[(k + 1) % kPerDecade] * decade;
  }

  void record(std::chrono::nanoseconds lateness) noexcept {
    const std::int64_t ns = lateness.count();
    std::size_t i = 0;
    while (i < kBuckets - 1 && ns > upper_edge_ns(i)) ++i;
    bump(counts_[i]);
    bump(total_);
    if (ns > max_ns_.load(std::memory_order_relaxed)) max_ns_.store(ns, std::memory_order_relaxed);
  }

  std::uint64_t count() const noexcept { return total_.load(std::memory_order_relaxed); }
  std::chrono::nanoseconds max() const noexcept {
    return std::chrono::nanoseconds{max_ns_.load(std::memory_order_relaxed)};
  }
  // The upper edge of the bucket holding quantile q (0..1), never above max(); 0 when empty.
  std::chrono::nanoseconds quantile(double q) const noexcept {
    const std::uint64_t n = count();
    if (n == 0) return std::chrono::nanoseconds{0};
    const auto rank = static_cast<std::uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * n));
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < kBuckets; ++i) {
      seen += counts_[i].load(std::memory_order_relaxed);
      if (seen >= std::max<std::uint64_t>(rank, 1)) {
        return std::chrono::nanoseconds{std::min(upper_edge_ns(i), max_ns_.load())};
      }
    }
    return max();
  }
  // Samples later than `limit` (counted by bucket: exact when `limit` is a bucket edge).
  std::uint64_t count_above(std::chrono::nanoseconds limit) const noexcept {
    std::uint64_t above = 0;
    for (std::size_t i = 0; i < kBuckets; ++i) {
      const std::int64_t lower = i == 0 ? INT64_MIN : upper_edge_ns(i - 1);
      if (lower >= limit.count()) above += counts_[i].load(std::memory_order_relaxed);
    }
    return above;
  }

 private:
  static void bump(std::atomic<std::uint64_t>& c) noexcept {
    c.store(c.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  }
  std::array<std::atomic<std::uint64_t>, kBuckets> counts_{};
  std::atomic<std::uint64_t> total_{0};
  std::atomic<std::int64_t> max_ns_{0};
};

// What a timing report prints of one loop.
struct LatenessSummary {
  std::uint64_t samples = 0;
  std::chrono::nanoseconds p50{0};
  std::chrono::nanoseconds p99{0};
  std::chrono::nanoseconds p999{0};
  std::chrono::nanoseconds max{0};
};

inline LatenessSummary summarize(const LatenessHistogram& h) noexcept {
  return {h.count(), h.quantile(0.5), h.quantile(0.99), h.quantile(0.999), h.max()};
}

}  // namespace weedspray::io
