// SPDX-License-Identifier: Apache-2.0
#include "io/emergency_outputs.hpp"

#include <sched.h>
#include <sys/ioctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <time.h>
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
// The gate (EmergencyOutputs::OrdinaryWrite). Both sides store, then load the other's flag, all
// sequentially consistent: a writer that did not see the gate closed is counted in flight when
// trigger() looks, so trigger() writes again after it (the Dekker pattern).
std::atomic<bool> g_triggered{false};
std::atomic<int> g_writes_in_flight{0};
// The ordinary writes this thread is inside: a handler running on a thread that crashed inside a
// write must not wait for it. Initial-exec TLS (the executable's static block) is read without
// any call, so a signal handler may read it. Changed after the shared count going in and before
// it coming out, so a signal between the two sees at most a write too many (a bounded wait).
__attribute__((tls_model("initial-exec"))) thread_local int t_writes_in_flight = 0;

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

// The signals whose default action ends the process (SIGTERM, SIGINT and SIGHUP excepted: the
// daemon's event loop takes them); the real-time signals are added at run time.
constexpr std::array<int, 18> kFatalSignals{
    SIGABRT, SIGSEGV, SIGBUS,  SIGFPE,  SIGILL,    SIGTRAP, SIGQUIT, SIGSYS, SIGXCPU,
    SIGXFSZ, SIGUSR1, SIGUSR2, SIGALRM, SIGVTALRM, SIGPROF, SIGIO,   SIGPWR, SIGSTKFLT};

constexpr std::size_t kMaxFatalSignals = 64;
// Every signal that gets the handler: kFatalSignals and the real-time signals.
std::size_t fatal_exit_signals(std::array<int, kMaxFatalSignals>& out) noexcept {
  std::size_t n = 0;
  for (int signal : kFatalSignals) out[n++] = signal;
  for (int signal = SIGRTMIN; signal <= SIGRTMAX && n < out.size(); ++signal) out[n++] = signal;
  return n;
}

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
  g_triggered.store(false);
}

std::size_t EmergencyOutputs::size() noexcept {
  return g_count.load();
}

bool EmergencyOutputs::get(std::size_t i, EmergencyWrite& out) noexcept {
  if (i >= g_count.load()) return false;
  out = g_writes[i];
  return true;
}

namespace {

int perform_all() noexcept {
  int failed = 0;
  const std::size_t n = g_count.load();
  for (std::size_t i = 0; i < n; ++i) {
    if (!perform(g_writes[i]) && !perform(g_writes[i])) ++failed;
  }
  return failed;
}

// Waits, sleeping (not spinning: a writer at a lower priority on this CPU must get to finish),
// until no other thread's ordinary write is in flight, or for at most kDrainLimitNs: a writer
// stuck in the kernel must not keep the process from dying.
void drain_ordinary_writes() noexcept {
  // Also at least kMinNaps naps, whatever the clock says: a virtual machine's clock can jump by
  // tens of ms while the writer has not run at all.
  constexpr int kMinNaps = 200;
  constexpr long kNapNs = 50'000;
  timespec start{};
  ::clock_gettime(CLOCK_MONOTONIC, &start);
  for (int naps = 0; g_writes_in_flight.load() - t_writes_in_flight > 0; ++naps) {
    timespec now{};
    ::clock_gettime(CLOCK_MONOTONIC, &now);
    const long elapsed = (now.tv_sec - start.tv_sec) * 1'000'000'000L + now.tv_nsec - start.tv_nsec;
    if (elapsed >= EmergencyOutputs::kDrainLimitNs && naps >= kMinNaps) return;
    const timespec nap{.tv_sec = 0, .tv_nsec = kNapNs};
    ::nanosleep(&nap, nullptr);
  }
}

}  // namespace

int EmergencyOutputs::trigger() noexcept {
  g_triggered.store(true);
  perform_all();  // at once: the lines safe as early as possible
  drain_ordinary_writes();
  return perform_all();  // after any write that was already past the gate
}

bool EmergencyOutputs::triggered() noexcept {
  return g_triggered.load();
}

EmergencyOutputs::OrdinaryWrite::OrdinaryWrite() noexcept {
  g_writes_in_flight.fetch_add(1);
  ++t_writes_in_flight;
  allowed_ = !g_triggered.load();
  // A write that found the gate closed writes the safe value: trigger() need not wait for it,
  // so only writes let through stay counted, and their count can only fall once it is closed.
  if (!allowed_) leave();
}

bool EmergencyOutputs::OrdinaryWrite::closed_since_entry() const noexcept {
  return allowed_ && g_triggered.load();
}

EmergencyOutputs::OrdinaryWrite::~OrdinaryWrite() {
  if (allowed_) leave();
}

void EmergencyOutputs::OrdinaryWrite::leave() noexcept {
  --t_writes_in_flight;
  g_writes_in_flight.fetch_sub(1);
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
  std::array<int, kMaxFatalSignals> signals{};
  const std::size_t n = fatal_exit_signals(signals);
  for (std::size_t i = 0; i < n; ++i) ::sigaction(signals[i], &action, nullptr);
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  ::sigaction(SIGPIPE, &ignore, nullptr);
  std::set_terminate(on_terminate);
}

}  // namespace weedspray::io
