// SPDX-License-Identifier: Apache-2.0
// A mutex with the priority-inheritance protocol, for simulated devices shared between the
// SCHED_FIFO loops and normal-priority threads (the daemon's main thread drives the simulated
// world and injects faults through the same lock). With a plain std::mutex, a SCHED_FIFO loop
// blocked on a lock held by a preempted normal thread waits for as long as the scheduler keeps
// that thread off the CPU (priority inversion: late valve edges and overruns under load); with
// PTHREAD_PRIO_INHERIT the holder runs at the waiter's priority until it unlocks.
// Hand-written: std::mutex offers no protocol attribute. Meets BasicLockable (std::lock_guard).
#pragma once

#include <pthread.h>

namespace weedspray::io::sim {

class PriorityInheritingMutex {
 public:
  PriorityInheritingMutex() noexcept {
    pthread_mutexattr_t attributes;
    pthread_mutexattr_init(&attributes);
    pthread_mutexattr_setprotocol(&attributes, PTHREAD_PRIO_INHERIT);
    pthread_mutex_init(&mutex_, &attributes);
    pthread_mutexattr_destroy(&attributes);
  }
  ~PriorityInheritingMutex() { pthread_mutex_destroy(&mutex_); }
  PriorityInheritingMutex(const PriorityInheritingMutex&) = delete;
  PriorityInheritingMutex& operator=(const PriorityInheritingMutex&) = delete;

  void lock() noexcept { pthread_mutex_lock(&mutex_); }
  void unlock() noexcept { pthread_mutex_unlock(&mutex_); }

 private:
  pthread_mutex_t mutex_;
};

}  // namespace weedspray::io::sim
