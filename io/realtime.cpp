// SPDX-License-Identifier: Apache-2.0
#include "io/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <signal.h>

#include <future>
#include <memory>
#include <string>

namespace weedspray::io {

namespace {

// The fatal-signal handlers (emergency_outputs.hpp) run on an alternate stack, because a stack
// overflow's SIGSEGV cannot be delivered on the overflowed stack; an alternate stack belongs to
// one thread, so each real-time thread sets up its own before its loop starts.
class ThreadSignalStack {
 public:
  ThreadSignalStack() : memory_(std::make_unique<unsigned char[]>(kBytes)) {
    stack_t stack{};
    stack.ss_sp = memory_.get();
    stack.ss_size = kBytes;
    installed_ = ::sigaltstack(&stack, nullptr) == 0;
  }
  ~ThreadSignalStack() {
    if (!installed_) return;
    stack_t off{};
    off.ss_flags = SS_DISABLE;
    ::sigaltstack(&off, nullptr);
  }
  ThreadSignalStack(const ThreadSignalStack&) = delete;
  ThreadSignalStack& operator=(const ThreadSignalStack&) = delete;

 private:
  static constexpr std::size_t kBytes = 64 * 1024;
  std::unique_ptr<unsigned char[]> memory_;
  bool installed_ = false;
};

// The memory lock (io/linux/memory_lock.hpp) locks a stack's pages as they are first touched:
// touching the top of the stack before the loop runs keeps a deeper call in the loop from
// taking a page fault.
constexpr std::size_t kPrefaultStackBytes = 256 * 1024;

[[gnu::noinline]] void prefault_stack() noexcept {
  unsigned char touch[kPrefaultStackBytes];
  for (std::size_t i = 0; i < kPrefaultStackBytes; i += 4096) touch[i] = 0;
  // The compiler may not drop the writes: the array escapes into an opaque asm.
  asm volatile("" : : "r"(touch) : "memory");
}

}  // namespace

std::string_view to_string(RtStatus status) noexcept {
  switch (status) {
    case RtStatus::kRealtime:
      return "SCHED_FIFO";
    case RtStatus::kNormalPriority:
      return "normal priority (by design)";
    case RtStatus::kNoPermission:
      return "normal priority: SCHED_FIFO not permitted (needs CAP_SYS_NICE or RLIMIT_RTPRIO)";
    case RtStatus::kFailed:
      return "normal priority: setting SCHED_FIFO failed";
  }
  return "unknown";
}

RtStatus apply_thread_role(ThreadRole role) noexcept {
  const ThreadPriority& p = thread_priority(role);
  const std::string name(p.name.substr(0, 15));
  pthread_setname_np(pthread_self(), name.c_str());
  if (p.fifo_priority == 0) return RtStatus::kNormalPriority;
  sched_param param{};
  param.sched_priority = p.fifo_priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (rc == 0) return RtStatus::kRealtime;
  return rc == EPERM ? RtStatus::kNoPermission : RtStatus::kFailed;
}

RealtimeThread::RealtimeThread(ThreadRole role, std::function<void(std::stop_token)> body) {
  std::promise<RtStatus> applied;
  std::future<RtStatus> status = applied.get_future();
  // The thread owns the promise, so it outlives set_value() however the threads interleave.
  thread_ = std::jthread(
      [role, applied = std::move(applied), body = std::move(body)](std::stop_token stop) mutable {
        const ThreadSignalStack signal_stack;
        prefault_stack();
        applied.set_value(apply_thread_role(role));
        body(stop);
      });
  status_ = status.get();
}

void RealtimeThread::stop_and_join() noexcept {
  if (thread_.joinable()) {
    thread_.request_stop();
    thread_.join();
  }
}

}  // namespace weedspray::io
