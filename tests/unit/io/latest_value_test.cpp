// SPDX-License-Identifier: Apache-2.0
#include "io/latest_value.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace weedspray::io {
namespace {

TEST(LatestValue, StartsWithInitialValueAndVersionZero) {
  LatestValue<Stamped<double>> slot;
  EXPECT_EQ(slot.version(), 0U);
  EXPECT_EQ(slot.read().value, 0.0);
}

TEST(LatestValue, ReadReturnsLastPublishedAndVersionCounts) {
  LatestValue<Stamped<double>> slot;
  slot.publish({1.5, std::chrono::nanoseconds{10}, 0});
  slot.publish({2.5, std::chrono::nanoseconds{20}, 3});
  Stamped<double> out;
  ASSERT_TRUE(slot.try_read(out));
  EXPECT_EQ(out.value, 2.5);
  EXPECT_EQ(out.sample_time, std::chrono::nanoseconds{20});
  EXPECT_EQ(out.error_count, 3U);
  EXPECT_EQ(slot.version(), 2U);
}

// A payload whose fields must always agree: a torn read would break the relation.
struct Triple {
  std::uint64_t a = 0;
  std::uint64_t b = 0;         // ~a
  std::uint64_t c = 0;         // a * 3
  std::uint8_t tail[13] = {};  // odd size: not a whole number of words
};

TEST(LatestValue, ConcurrentReaderNeverSeesATornValue) {
  LatestValue<Triple> slot;
  std::atomic<bool> done{false};
  std::uint64_t torn = 0;
  std::uint64_t reads = 0;
  std::uint64_t last_seen = 0;
  bool monotonic = true;
  std::thread reader([&] {
    while (!done.load(std::memory_order_acquire)) {
      Triple t;
      if (!slot.try_read(t)) continue;
      // The slot's initial value (all zero) is not a Triple the writer made: on a loaded machine
      // the reader runs before the first publish and read it as "torn" a million times.
      if (t.a == 0) continue;
      ++reads;
      if (t.b != ~t.a || t.c != t.a * 3 || t.tail[12] != static_cast<std::uint8_t>(t.a)) ++torn;
      if (t.a < last_seen) monotonic = false;
      last_seen = t.a;
    }
  });
  for (std::uint64_t i = 1; i <= 2'000'000; ++i) {
    Triple t;
    t.a = i;
    t.b = ~i;
    t.c = i * 3;
    t.tail[12] = static_cast<std::uint8_t>(i);
    slot.publish(t);
  }
  done.store(true, std::memory_order_release);
  reader.join();
  EXPECT_EQ(torn, 0U);
  EXPECT_TRUE(monotonic);
  EXPECT_GT(reads, 0U);
  EXPECT_EQ(slot.read().a, 2'000'000U);
}

}  // namespace
}  // namespace weedspray::io
