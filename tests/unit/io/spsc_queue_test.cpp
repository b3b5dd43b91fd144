// SPDX-License-Identifier: Apache-2.0
#include "io/spsc_queue.hpp"

#include <gtest/gtest.h>

#include <thread>

namespace weedspray::io {
namespace {

TEST(SpscQueue, FifoOrderAndFullEmpty) {
  SpscQueue<int, 4> q;
  EXPECT_FALSE(q.try_pop().has_value());
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(q.try_push(i));
  EXPECT_FALSE(q.try_push(99)) << "a full queue must refuse";
  EXPECT_EQ(q.size(), 4U);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(q.try_pop(), i);
  EXPECT_FALSE(q.try_pop().has_value());
  // Wrap around the ring several times.
  for (int round = 0; round < 10; ++round) {
    EXPECT_TRUE(q.try_push(round));
    EXPECT_TRUE(q.try_push(round + 100));
    EXPECT_EQ(q.try_pop(), round);
    EXPECT_EQ(q.try_pop(), round + 100);
  }
}

TEST(SpscQueue, ConcurrentProducerConsumerLoseNothing) {
  SpscQueue<std::uint64_t, 64> q;
  constexpr std::uint64_t kItems = 1'000'000;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kItems;) {
      if (q.try_push(i)) ++i;
    }
  });
  std::uint64_t expected = 0;
  bool in_order = true;
  while (expected < kItems) {
    if (auto v = q.try_pop()) {
      if (*v != expected) in_order = false;
      ++expected;
    }
  }
  producer.join();
  EXPECT_TRUE(in_order);
  EXPECT_FALSE(q.try_pop().has_value());
}

}  // namespace
}  // namespace weedspray::io
