#include "io/emergency_outputs.hpp"

#include <sched.h>
#include <sys/ioctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <exception>

namespace weedspray::io {
namespace {

std::array<EmergencyWrite, EmergencyOutputs::kCapacity> g_writes{};
std::atomic<std::size_t> g_count{0};
std::atomic<int> g_urgent_priority{0};

// The highest SCHED_FIFO priority this process may take: RLIMIT_RTPRIO's (the unit sets
// LimitRTPRIO=90, above the valve thread's 80), or the policy's maximum where the limit is 0
// and only CAP_SYS_NICE (root) allows it.
int highest_permitted_fifo_priority() noexcept {
  const int max = ::sched_get_priority_max(SCHED_FIFO);
  rlimit limit{};
  if (::getrlimit(RLIMIT_RTPRIO, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY ||
      limit.rlim_cur == 0)
    return max;
  return static_cast<int>(std::min<rlim_t>(limit.rlim_cur, static_cast<rlim_t>(max)));
}

constexpr std::array<int, 5> kFatalSignals{SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL};

bool perform(const EmergencyWrite& w) noexcept {
  if (w.fd < 0) return false;
  if (w.kind == EmergencyWrite::Kind::kIoctl) {
    // The payload array outlives the call; the kernel reads the struct it points to.
    return ::ioctl(w.fd, w.request, const_cast<unsigned char*>(w.payload.data())) >= 0;
  }
  return ::pwrite(w.fd, w.payload.data(), w.length, 0) == static_cast<ssize_t>(w.length);
}

void on_fatal_signal(int signal) {
  const int saved_errno = errno;
  EmergencyOutputs::make_calling_thread_urgent();
  EmergencyOutputs::trigger();
  static constexpr char kMessage[] = "weedsprayd: fatal signal: outputs written safe\n";
  [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
  errno = saved_errno;
  // SA_RESETHAND restored the default action: die of the same signal.
  ::raise(signal);
}

[[noreturn]] void on_terminate() {
  EmergencyOutputs::make_calling_thread_urgent();
  EmergencyOutputs::trigger();
  static constexpr char kMessage[] = "weedsprayd: std::terminate: outputs written safe\n";
  [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
  std::abort();
}

}  // namespace

bool EmergencyOutputs::add(const EmergencyWrite& write) noexcept {
  const std::size_t n = g_count.load();
  if (n >= kCapacity) return false;
  g_writes[n] = write;
  g_count.store(n + 1);
  return true;
}

void EmergencyOutputs::clear() noexcept {
  g_count.store(0);
}

std::size_t EmergencyOutputs::size() noexcept {
  return g_count.load();
}

bool EmergencyOutputs::get(std::size_t i, EmergencyWrite& out) noexcept {
  if (i >= g_count.load()) return false;
  out = g_writes[i];
  return true;
}

int EmergencyOutputs::trigger() noexcept {
  int failed = 0;
  const std::size_t n = g_count.load();
  for (std::size_t i = 0; i < n; ++i) {
    if (!perform(g_writes[i]) && !perform(g_writes[i])) ++failed;
  }
  return failed;
}

bool EmergencyOutputs::make_calling_thread_urgent() noexcept {
  const int priority = g_urgent_priority.load();
  if (priority <= 0) return false;
  const sched_param param{.sched_priority = priority};
  // The raw syscall (pid 0 = this thread), not pthread_setschedparam: no library state touched.
  return ::syscall(SYS_sched_setscheduler, 0, SCHED_FIFO, &param) == 0;
}

int EmergencyOutputs::urgent_priority() noexcept {
  return g_urgent_priority.load();
}

void install_fatal_exit_handlers() noexcept {
  g_urgent_priority.store(highest_permitted_fifo_priority());
  // A stack overflow's SIGSEGV cannot run on the overflowed stack.
  static std::array<unsigned char, 64 * 1024> alternate_stack{};
  stack_t ss{};
  ss.ss_sp = alternate_stack.data();
  ss.ss_size = alternate_stack.size();
  ::sigaltstack(&ss, nullptr);
  struct sigaction action {};
  action.sa_handler = on_fatal_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND | SA_ONSTACK | SA_NODEFER;
  for (int signal : kFatalSignals) ::sigaction(signal, &action, nullptr);
  std::set_terminate(on_terminate);
}

}  // namespace weedspray::io
