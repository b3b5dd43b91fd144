// SPDX-License-Identifier: Apache-2.0
// The fatal-exit path: a child process registers a file-backed safe write (the same pwrite a
// sysfs DAC attribute gets), "opens a valve" by writing another value, then dies of a fatal
// signal or std::terminate. The file must hold the safe value afterwards, and the child must
// still die of the signal (re-raised), so systemd sees the crash.
#include "io/emergency_outputs.hpp"

#include <fcntl.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <thread>

#include "io/realtime.hpp"

namespace weedspray::io {
namespace {

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

enum class Death { kSignal, kEscapedException, kReadOnlyStore, kStackOverflowInRealtimeThread };

// Recurses until the stack's guard page; the opaque limit keeps the compiler from seeing an
// endless recursion (or turning it into a loop).
volatile int g_recursion_limit = 1 << 30;
int recurse_into_the_guard_page(int depth) {
  volatile char frame[512];
  frame[0] = static_cast<char>(depth);
  if (depth >= g_recursion_limit) return frame[0];
  return recurse_into_the_guard_page(depth + 1) + frame[0];
}

// In a child: writes "OPEN" to the file (the valve), registers "SAFE" as its fatal-exit write
// when armed, installs the handlers; returns the file's descriptor.
int open_the_valve_and_arm(const std::filesystem::path& file, bool armed) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0 || ::pwrite(fd, "OPEN\n", 5, 0) != 5) ::_exit(90);
  if (armed) {
    EmergencyWrite safe;
    safe.kind = EmergencyWrite::Kind::kPwrite;
    safe.fd = fd;
    std::memcpy(safe.payload.data(), "SAFE\n", 5);
    safe.length = 5;
    EmergencyOutputs::add(safe);
  }
  install_fatal_exit_handlers();
  return fd;
}

// Runs `die` in a child with the handlers installed; returns the child's wait status.
int run_child(const std::filesystem::path& file, Death how, int signal, bool armed) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    open_the_valve_and_arm(file, armed);
    switch (how) {
      case Death::kSignal:
        ::raise(signal);
        break;
      case Death::kEscapedException:
        // An exception leaving a thread's function calls std::terminate.
        std::thread([] { throw std::runtime_error("escaped"); }).join();
        break;
      case Death::kReadOnlyStore: {
        // A store to a read-only page: a real SIGSEGV from the MMU, and no undefined behaviour
        // for UBSan to stop first (as a null store would be in the sanitizer build).
        void* page = ::mmap(nullptr, 4096, PROT_READ, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        *static_cast<volatile int*>(page) = 1;
        break;
      }
      case Death::kStackOverflowInRealtimeThread: {
        RealtimeThread overflowing(ThreadRole::kValvePwm, [](std::stop_token) {
          [[maybe_unused]] const int sum = recurse_into_the_guard_page(0);
        });
        overflowing.stop_and_join();
        break;
      }
    }
    ::_exit(91);  // not reached when the death came
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

// Whether a child with no handler installed dies of `signal` raised on itself: qemu-user
// (the arm64 tests) keeps some real-time signals for itself and never delivers them.
bool delivered_here(int signal) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::raise(signal);
    ::_exit(91);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFSIGNALED(status) && WTERMSIG(status) == signal;
}

class FatalExit : public ::testing::TestWithParam<int> {};

TEST_P(FatalExit, WritesTheSafeValueAndDiesOfTheSameSignal) {
  if (!delivered_here(GetParam())) {
    GTEST_SKIP() << "signal " << GetParam() << " is not delivered on this machine (an emulator)";
  }
  const auto file = std::filesystem::temp_directory_path() /
                    ("weedspray_emergency_" + std::to_string(GetParam()));
  const int status = run_child(file, Death::kSignal, GetParam(), true);
  ASSERT_TRUE(WIFSIGNALED(status)) << "status " << status;
  EXPECT_EQ(WTERMSIG(status), GetParam());
  EXPECT_EQ(read_file(file), "SAFE\n");
  // Without the registered write the "valve" stays as it was: the check above can fail.
  const int unarmed = run_child(file, Death::kSignal, GetParam(), false);
  EXPECT_TRUE(WIFSIGNALED(unarmed));
  EXPECT_EQ(read_file(file), "OPEN\n");
  std::filesystem::remove(file);
}

INSTANTIATE_TEST_SUITE_P(EverySignal, FatalExit,
                         ::testing::Values(SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGTRAP,
                                           SIGQUIT, SIGSYS, SIGXCPU, SIGXFSZ, SIGUSR1, SIGUSR2,
                                           SIGALRM, SIGVTALRM, SIGPROF, SIGIO, SIGPWR, SIGSTKFLT,
                                           SIGRTMIN, SIGRTMIN + 5, SIGRTMAX));

// No signal whose default action ends the process is left at that default: each one either
// writes the outputs safe first or is ignored. The exceptions are the event loop's own
// (SIGTERM, SIGINT, SIGHUP) and those nothing can catch.
TEST(FatalExit, EveryTerminatingSignalIsHandledOrIgnored) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    install_fatal_exit_handlers();
    // Default actions that do not end the process: ignore, continue, stop.
    const std::array<int, 9> not_terminating{SIGCHLD, SIGCONT, SIGURG,  SIGWINCH, SIGSTOP,
                                             SIGTSTP, SIGTTIN, SIGTTOU, SIGKILL};
    const std::array<int, 3> event_loop{SIGTERM, SIGINT, SIGHUP};
    for (int signal = 1; signal <= SIGRTMAX; ++signal) {
      if (signal > SIGSYS && signal < SIGRTMIN) continue;  // the C library's own
      if (std::find(not_terminating.begin(), not_terminating.end(), signal) !=
              not_terminating.end() ||
          std::find(event_loop.begin(), event_loop.end(), signal) != event_loop.end())
        continue;
      struct sigaction action {};
      if (::sigaction(signal, nullptr, &action) != 0) ::_exit(100);
      if (action.sa_handler == SIG_DFL) ::_exit(signal);  // names the signal left at default
    }
    ::_exit(0);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 0) << "signal " << WEXITSTATUS(status) << " ("
                                    << strsignal(WEXITSTATUS(status)) << ") left at its default";
}

// SIGPIPE (a write to a closed socket or pipe) is ignored: the write fails with EPIPE and the
// process goes on, with the outputs as they were.
TEST(FatalExit, SigpipeIsIgnored) {
  const auto file = std::filesystem::temp_directory_path() / "weedspray_emergency_sigpipe";
  const int status = run_child(file, Death::kSignal, SIGPIPE, true);
  ASSERT_TRUE(WIFEXITED(status)) << "status " << status;
  EXPECT_EQ(WEXITSTATUS(status), 91);
  EXPECT_EQ(read_file(file), "OPEN\n");
  std::filesystem::remove(file);
}

TEST(FatalExit, AnExceptionEscapingAThreadWritesSafeAndAborts) {
  const auto file = std::filesystem::temp_directory_path() / "weedspray_emergency_terminate";
  const int status = run_child(file, Death::kEscapedException, 0, true);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGABRT);
  EXPECT_EQ(read_file(file), "SAFE\n");
  std::filesystem::remove(file);
}

TEST(FatalExit, ARealSegfaultWritesSafe) {
  const auto file = std::filesystem::temp_directory_path() / "weedspray_emergency_segv";
  const int status = run_child(file, Death::kReadOnlyStore, 0, true);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGSEGV);
  EXPECT_EQ(read_file(file), "SAFE\n");
  std::filesystem::remove(file);
}

// A real-time thread's stack overflow: the SIGSEGV is delivered on that thread's own alternate
// stack (each RealtimeThread sets one up), so the handler runs and the "valve" is written safe.
TEST(FatalExit, AStackOverflowInARealtimeThreadWritesSafe) {
  const auto file = std::filesystem::temp_directory_path() / "weedspray_emergency_overflow";
  const int status = run_child(file, Death::kStackOverflowInRealtimeThread, 0, true);
  ASSERT_TRUE(WIFSIGNALED(status)) << "status " << status;
  EXPECT_EQ(WTERMSIG(status), SIGSEGV);
  EXPECT_EQ(read_file(file), "SAFE\n");
  std::filesystem::remove(file);
}

// The handler first lifts its thread above the daemon's real-time threads, to the highest
// priority RLIMIT_RTPRIO allows (in a child: the handlers are process-wide).
TEST(FatalExit, TheHandlerThreadBecomesTheMostUrgent) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    // RLIMIT_RTPRIO 7 where it can be set (raising the hard limit needs CAP_SYS_RESOURCE);
    // otherwise the limit as it is, 0 meaning the policy's maximum (root's CAP_SYS_NICE).
    const rlimit seven{.rlim_cur = 7, .rlim_max = 7};
    rlimit limit{};
    if (::setrlimit(RLIMIT_RTPRIO, &seven) != 0 && ::getrlimit(RLIMIT_RTPRIO, &limit) != 0)
      ::_exit(4);
    const int expected = ::getrlimit(RLIMIT_RTPRIO, &limit) == 0 && limit.rlim_cur > 0 &&
                                 limit.rlim_cur != RLIM_INFINITY
                             ? static_cast<int>(limit.rlim_cur)
                             : ::sched_get_priority_max(SCHED_FIFO);
    install_fatal_exit_handlers();
    int result = 5;
    std::thread([&] {
      if (!EmergencyOutputs::make_calling_thread_urgent()) {
        result = ::geteuid() == 0 ? 6 : 3;  // root (CI) is always permitted
        return;
      }
      sched_param param{};
      ::sched_getparam(0, &param);
      result = ::sched_getscheduler(0) == SCHED_FIFO && param.sched_priority == expected &&
                       EmergencyOutputs::urgent_priority() == expected
                   ? 0
                   : 2;
    }).join();
    ::_exit(result);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  if (WEXITSTATUS(status) == 3) GTEST_SKIP() << "SCHED_FIFO not permitted for this user";
  EXPECT_EQ(WEXITSTATUS(status), 0)
      << "2: not SCHED_FIFO at the RLIMIT_RTPRIO priority; 6: refused as root";
  // The main process is untouched: the handlers were installed in the child only.
  EXPECT_EQ(::sched_getscheduler(0), SCHED_OTHER);
}

// A writer thread keeps "opening the valve" through the gate, as the valve PWM thread does on
// the other CPU, while the main thread dies: the file must hold the safe value when the process
// is gone. Without the gate the writer's next "OPEN" lands after the handler's "SAFE" (checked by
// hand: the writer ignoring allowed() fails this test, and so does trigger() without its second
// round).
int die_while_a_thread_writes(const std::filesystem::path& file, int signal) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = open_the_valve_and_arm(file, true);
    std::atomic<int> writes{0};
    std::thread writer([&] {
      for (;;) {
        const EmergencyOutputs::OrdinaryWrite gate;
        // Every other write is held up past its gate, as a writer preempted between the gate
        // and its ioctl is: trigger() must write again after it.
        // (A busy wait: a sleeping writer would simply die with the process.)
        if (writes.load() % 2 == 1) {
          const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(30);
          while (std::chrono::steady_clock::now() < until) {
          }
        }
        [[maybe_unused]] const ssize_t n = ::pwrite(fd, gate.allowed() ? "OPEN\n" : "SAFE\n", 5, 0);
        writes.fetch_add(1);
      }
    });
    writer.detach();
    while (writes.load() < 100) std::this_thread::yield();
    ::raise(signal);
    ::_exit(91);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

TEST(FatalExit, NoOrdinaryWriteLandsAfterTheSafeWrites) {
  const auto file = std::filesystem::temp_directory_path() / "weedspray_emergency_race";
  for (int signal : {SIGSEGV, SIGABRT}) {
    for (int death = 0; death < 40; ++death) {
      const int status = die_while_a_thread_writes(file, signal);
      ASSERT_TRUE(WIFSIGNALED(status)) << "status " << status;
      ASSERT_EQ(WTERMSIG(status), signal);
      ASSERT_EQ(read_file(file), "SAFE\n") << "death " << death << " of signal " << signal;
    }
  }
  std::filesystem::remove(file);
}

TEST(EmergencyOutputs, TheGateClosesWhenTriggeredAndClearOpensIt) {
  EmergencyOutputs::clear();
  EXPECT_TRUE(EmergencyOutputs::OrdinaryWrite().allowed());
  EXPECT_FALSE(EmergencyOutputs::triggered());
  EXPECT_EQ(EmergencyOutputs::trigger(), 0) << "nothing registered, nothing failed";
  EXPECT_TRUE(EmergencyOutputs::triggered());
  EXPECT_FALSE(EmergencyOutputs::OrdinaryWrite().allowed());
  EmergencyOutputs::clear();
  EXPECT_TRUE(EmergencyOutputs::OrdinaryWrite().allowed());
}

// A writer past the gate when a handler closes it is told so after its write (it may have landed
// after the handler's safe one, so the writer writes its safe value at once); one that found the
// gate closed wrote the safe value already and is not told to write again.
TEST(EmergencyOutputs, AWriteOverlappingTheTriggerIsToldItClosedMeanwhile) {
  EmergencyOutputs::clear();
  std::atomic<bool> inside{false};
  bool closed_going_in = true;
  bool closed_coming_out = false;
  std::thread writer([&] {
    const EmergencyOutputs::OrdinaryWrite write;
    closed_going_in = write.closed_since_entry();
    inside = true;
    while (!EmergencyOutputs::triggered()) std::this_thread::yield();
    closed_coming_out = write.closed_since_entry();
  });
  while (!inside) std::this_thread::yield();
  EmergencyOutputs::trigger();  // waits for the writer, which leaves once the gate is closed
  writer.join();
  EXPECT_FALSE(closed_going_in);
  EXPECT_TRUE(closed_coming_out);
  EXPECT_FALSE(EmergencyOutputs::OrdinaryWrite().closed_since_entry());
  EmergencyOutputs::clear();
  EXPECT_FALSE(EmergencyOutputs::OrdinaryWrite().closed_since_entry());
}

// Another thread's write stuck in flight delays the dying process by at most kDrainLimitNs; the
// handler's own thread's write (it crashed inside it) delays it not at all.
TEST(EmergencyOutputs, TriggerWaitsForAnotherThreadsWriteOnlySoLong) {
  EmergencyOutputs::clear();
  std::atomic<bool> inside{false};
  std::atomic<bool> leave{false};
  std::thread stuck([&] {
    const EmergencyOutputs::OrdinaryWrite write;
    inside = true;
    while (!leave) std::this_thread::yield();
  });
  while (!inside) std::this_thread::yield();
  auto start = std::chrono::steady_clock::now();
  EmergencyOutputs::trigger();
  const auto waited = std::chrono::steady_clock::now() - start;
  leave = true;
  stuck.join();
  EXPECT_GE(waited, std::chrono::nanoseconds(EmergencyOutputs::kDrainLimitNs));
  EXPECT_LT(waited, std::chrono::milliseconds(1000)) << "bounded, not forever";

  EmergencyOutputs::clear();
  const EmergencyOutputs::OrdinaryWrite own;
  start = std::chrono::steady_clock::now();
  EmergencyOutputs::trigger();
  EXPECT_LT(std::chrono::steady_clock::now() - start,
            std::chrono::nanoseconds(EmergencyOutputs::kDrainLimitNs / 2))
      << "the calling thread's own write is not waited for";
  EmergencyOutputs::clear();
}

TEST(EmergencyOutputs, CapacityIsBoundedAndClearForgets) {
  EmergencyOutputs::clear();
  EmergencyWrite w;
  for (std::size_t i = 0; i < EmergencyOutputs::kCapacity; ++i)
    EXPECT_TRUE(EmergencyOutputs::add(w));
  EXPECT_FALSE(EmergencyOutputs::add(w));
  EXPECT_EQ(EmergencyOutputs::trigger(), static_cast<int>(EmergencyOutputs::kCapacity))
      << "fd -1 writes fail and are counted";
  EmergencyOutputs::clear();
  EXPECT_EQ(EmergencyOutputs::size(), 0U);
}

}  // namespace
}  // namespace weedspray::io
