// SPDX-License-Identifier: Apache-2.0
#include "daemon/test_crash_hook.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdlib>
#include <cstring>

namespace weedspray::daemon {
namespace {

enum Fault : int { kNone = 0, kAbort = 1, kSegv = 2, kHang = 3 };
std::atomic<int> g_requested{kNone};

void on_request(int signal) {
  g_requested.store(signal - SIGRTMIN);
}

}  // namespace

bool install_test_crash_hook() {
  const char* enabled = std::getenv("WEEDSPRAY_TEST_CRASH_HOOK");
  if (enabled == nullptr || std::strcmp(enabled, "1") != 0) return false;
  for (int fault : {kAbort, kSegv, kHang}) std::signal(SIGRTMIN + fault, on_request);
  return true;
}

void run_requested_test_fault() {
  switch (g_requested.load()) {
    case kAbort:
      std::abort();
    case kSegv: {
      // A real fault, not raise(SIGSEGV): a store to a page mapped read-only.
      void* page = mmap(nullptr, 4096, PROT_READ, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      *static_cast<volatile int*>(page) = 1;
      std::abort();  // not reached
    }
    case kHang:
      for (;;) pause();  // the loop makes no progress: the watchdog is no longer fed
    default:
      return;
  }
}

std::chrono::milliseconds test_reload_delay() {
  static const std::chrono::milliseconds delay = [] {
    const char* text = std::getenv("WEEDSPRAY_TEST_RELOAD_DELAY_MS");
    return std::chrono::milliseconds(text != nullptr ? std::atol(text) : 0);
  }();
  return delay;
}

}  // namespace weedspray::daemon
