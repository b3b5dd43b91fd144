#include "io/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <future>
#include <string>

namespace weedspray::io {

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

int lock_memory() noexcept {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) return -errno;
  return 0;
}

RealtimeThread::RealtimeThread(ThreadRole role, std::function<void(std::stop_token)> body) {
  std::promise<RtStatus> applied;
  std::future<RtStatus> status = applied.get_future();
  // The thread owns the promise, so it outlives set_value() however the threads interleave.
  thread_ = std::jthread(
      [role, applied = std::move(applied), body = std::move(body)](std::stop_token stop) mutable {
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
