// SPDX-License-Identifier: Apache-2.0
// io::sim::PriorityInheritingMutex against the inversion it exists for, on one CPU: a
// normal-priority thread holds the lock, a SCHED_FIFO hog takes the CPU, and a higher SCHED_FIFO
// waiter blocks on the lock. With priority inheritance the holder runs at the waiter's priority,
// finishes its 20 ms and hands over; without it the waiter would wait out the whole 400 ms hog.
#include "io/sim/priority_inheriting_mutex.hpp"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>

namespace weedspray::io::sim {
namespace {

using namespace std::chrono_literals;
using SteadyClock = std::chrono::steady_clock;

bool pin_to_cpu0() {
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  CPU_SET(0, &cpus);
  return pthread_setaffinity_np(pthread_self(), sizeof(cpus), &cpus) == 0;
}

bool set_fifo(int priority) {
  const sched_param param{.sched_priority = priority};
  return pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
}

void spin_for(std::chrono::nanoseconds duration) {
  const auto end = SteadyClock::now() + duration;
  while (SteadyClock::now() < end) {
  }
}

TEST(PriorityInheritingMutex, ANormalHolderIsBoostedPastASchedFifoHog) {
  {
    std::thread probe([] {});
    sched_param param{.sched_priority = 1};
    const bool permitted = pthread_setschedparam(probe.native_handle(), SCHED_FIFO, &param) == 0;
    probe.join();
    if (!permitted) GTEST_SKIP() << "SCHED_FIFO not permitted (needs root or CAP_SYS_NICE)";
  }
  PriorityInheritingMutex mutex;
  std::atomic<bool> held{false}, hog_running{false}, setup_ok{true};
  std::chrono::nanoseconds waited{};

  std::thread holder([&] {
    setup_ok = setup_ok && pin_to_cpu0();
    std::lock_guard lock(mutex);
    held = true;
    spin_for(20ms);  // the critical section: needs the CPU the hog takes
  });
  while (!held) std::this_thread::yield();
  std::thread hog([&] {
    setup_ok = setup_ok && pin_to_cpu0() && set_fifo(20);
    hog_running = true;
    spin_for(400ms);
  });
  while (!hog_running) std::this_thread::yield();
  std::thread waiter([&] {
    // Priority first: pinned while still normal, it could not run on the hog's CPU to raise it.
    setup_ok = setup_ok && set_fifo(30) && pin_to_cpu0();
    const auto start = SteadyClock::now();
    std::lock_guard lock(mutex);
    waited = SteadyClock::now() - start;
  });
  waiter.join();
  holder.join();
  hog.join();
  ASSERT_TRUE(setup_ok) << "pinning or SCHED_FIFO failed";
  EXPECT_LT(waited, 200ms) << "the holder was not boosted: the waiter sat behind the hog";
}

}  // namespace
}  // namespace weedspray::io::sim
