// SPDX-License-Identifier: Apache-2.0
// The camera workers' shared inference gate serves callers in the order they asked.
#include <gtest/gtest.h>

#include <chrono>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "daemon/sprayer/inference_gate.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

void wait_until_waiting(const InferenceGate& gate, std::uint64_t callers) {
  const auto give_up = std::chrono::steady_clock::now() + 10s;
  while (gate.waiting() < callers && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(1ms);
  }
  ASSERT_EQ(gate.waiting(), callers);
}

class Order {
 public:
  void add(char who) {
    std::lock_guard lock(mutex_);
    order_.push_back(who);
  }
  std::string str() {
    std::lock_guard lock(mutex_);
    return {order_.begin(), order_.end()};
  }

 private:
  std::mutex mutex_;
  std::vector<char> order_;
};

TEST(InferenceGate, ServesCallersInTheOrderTheyAsked) {
  InferenceGate gate;
  Order order;
  std::optional<InferenceGate::Turn> held(gate.acquire());
  EXPECT_EQ(gate.waiting(), 0U);
  std::vector<std::jthread> callers;
  for (char who : std::string("ABCD")) {
    callers.emplace_back([&gate, &order, who] {
      const auto turn = gate.acquire();
      order.add(who);
    });
    wait_until_waiting(gate, callers.size());
  }
  held.reset();
  callers.clear();  // joins
  EXPECT_EQ(order.str(), "ABCD");
  EXPECT_EQ(gate.waiting(), 0U);
}

// A worker that asks again the moment it releases (a camera whose frames keep coming) does
// not overtake one already waiting: no camera starves the others.
TEST(InferenceGate, AskingAgainAtOnceQueuesBehindTheWaiting) {
  InferenceGate gate;
  Order order;
  for (int round = 0; round < 20; ++round) {
    std::optional<InferenceGate::Turn> held(gate.acquire());
    std::jthread other([&] {
      const auto turn = gate.acquire();
      order.add('O');
      std::this_thread::sleep_for(1ms);
    });
    wait_until_waiting(gate, 1);
    held.reset();
    held.emplace(gate.acquire());  // straight back in
    order.add('H');
    held.reset();
  }
  std::string expected;
  for (int round = 0; round < 20; ++round) expected += "OH";
  EXPECT_EQ(order.str(), expected);
}

}  // namespace
}  // namespace weedspray::daemon
