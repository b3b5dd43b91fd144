// SPDX-License-Identifier: Apache-2.0
// Fail-safe writes for the exits that run no normal code: a fatal signal (the systemd
// watchdog's SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL, or any other signal whose default action
// ends the process) or std::terminate (an exception that escaped a thread or a C callback).
// Each output device registers, at start-up, one write that puts it in its safe state as a
// single syscall on a file descriptor it already holds (a GPIO line handle's SET_LINE_VALUES
// ioctl, a pwrite of a sysfs attribute): the handler then runs only async-signal-safe calls - no
// allocation, no locks, no library - and re-raises the signal so the process still dies of it (core
// dump, systemd's Restart=on-failure, the exit status). kill -9 and power loss run nothing in the
// process: the exit watcher (the same writes on copies of these descriptors,
// daemon/backends/emergency_write_handoff.hpp), ExecStopPost (weedspray-safe-outputs) and the
// heartbeat relay cover those. Hand-written because it must run inside a signal handler:
// fixed storage, no allocation.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace weedspray::io {

struct EmergencyWrite {
  enum class Kind : std::uint8_t { kIoctl, kPwrite };
  Kind kind = Kind::kPwrite;
  int fd = -1;
  unsigned long request = 0;  // kIoctl: the request number; the payload is its argument
  std::array<unsigned char, 64> payload{};
  std::size_t length = 0;  // kPwrite: bytes written at offset 0
};

class EmergencyOutputs {
 public:
  static constexpr std::size_t kCapacity = 16;
  // Start-up only (not thread-safe against trigger()). False when full.
  static bool add(const EmergencyWrite& write) noexcept;
  // Forgets every write (their descriptors are about to close) and opens the gate again.
  static void clear() noexcept;
  static std::size_t size() noexcept;
  // The i-th registered write (false past the end): what the daemon hands its exit watcher.
  static bool get(std::size_t i, EmergencyWrite& out) noexcept;
  // Closes the gate (below), performs every write (each retried once on failure), waits up to
  // kDrainLimitNs for other threads' ordinary writes already past the gate to end, and performs
  // every write again; returns how many writes failed in the last round. Async-signal-safe.
  static int trigger() noexcept;
  static constexpr long kDrainLimitNs = 50'000'000;
  // True once trigger() has begun (until clear()).
  static bool triggered() noexcept;

  // The gate every ordinary write of a registered output passes, held across the write. Another
  // thread - the valve PWM thread at SCHED_FIFO on the other CPU - may be about to write a valve
  // open while a fatal-signal handler writes the lines safe; without the gate its write could
  // land after the safe one and open the valve until the process is gone. A writer that finds
  // the gate closed (allowed() false) writes its safe value instead; trigger() writes again
  // after the writes it saw in flight have ended. Lock-free: the real-time writers may hold it.
  class OrdinaryWrite {
   public:
    OrdinaryWrite() noexcept;
    ~OrdinaryWrite();
    OrdinaryWrite(const OrdinaryWrite&) = delete;
    OrdinaryWrite& operator=(const OrdinaryWrite&) = delete;
    bool allowed() const noexcept { return allowed_; }
    // True when the gate was open going in and a fatal-exit handler has closed it since: the
    // write just made may have landed after the handler's safe one (a writer preempted between
    // the gate and its syscall - by the handler itself on a one-CPU board, or a virtual CPU
    // descheduled by its host). The writer then writes its safe value at once, so such a late
    // write holds a valve open for one syscall, not until the handler's second round.
    bool closed_since_entry() const noexcept;

   private:
    void leave() noexcept;
    bool allowed_;
  };
  // Puts the calling thread at SCHED_FIFO above every real-time thread of the daemon (the
  // highest priority RLIMIT_RTPRIO allows, as of install_fatal_exit_handlers()), so the safe
  // writes are not kept waiting by the valve or pressure threads, or by the rest of the machine.
  // One raw syscall: async-signal-safe in practice. False where not permitted (then unchanged).
  static bool make_calling_thread_urgent() noexcept;
  static int urgent_priority() noexcept;  // 0 before install_fatal_exit_handlers()
};

// Installs the handlers (SA_ONSTACK on an alternate stack, so a stack overflow's SIGSEGV is
// handled too) and a std::terminate handler that triggers, logs nothing and aborts. Every
// signal whose default action ends the process gets the handler (the crashes above, SIGTRAP
// from __builtin_trap on aarch64, SIGQUIT, SIGSYS, SIGXCPU from RLIMIT_RTTIME, SIGXFSZ, SIGUSR1/2,
// the timer signals, SIGIO, SIGPWR, SIGSTKFLT and the real-time signals), except SIGTERM,
// SIGINT and SIGHUP, which the daemon's event loop takes, and SIGKILL, which nothing can catch;
// SIGPIPE is ignored (a write to a closed pipe or socket fails with EPIPE instead).
void install_fatal_exit_handlers() noexcept;

}  // namespace weedspray::io
