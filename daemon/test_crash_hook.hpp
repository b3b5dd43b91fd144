// SPDX-License-Identifier: Apache-2.0
// Test-only faults for the hardware-in-the-loop scenario (tests/vm-systemd): an abort, a
// segmentation fault and a hung main loop, each raised inside the running daemon so the test
// can show the fail-safe paths (io/emergency_outputs.hpp, the systemd watchdog) put the outputs
// safe. Off unless the environment has WEEDSPRAY_TEST_CRASH_HOOK=1 (set only by the test's
// systemd drop-in): without it no handler is installed and these real-time signals keep their
// default action (the process ends at once, no fault in the main loop, nothing logged).
//   SIGRTMIN+1: abort()     SIGRTMIN+2: store to a read-only page     SIGRTMIN+3: hang
// The fault happens in the main loop's thread at its next tick, not in the signal handler.
#pragma once

#include <chrono>

namespace weedspray::daemon {

// Installs the handlers when enabled; returns whether it did.
bool install_test_crash_hook();
// Main loop: performs a requested fault (never returns then); otherwise nothing.
void run_requested_test_fault();

// How long each configuration reload waits on its thread before it reads the files:
// WEEDSPRAY_TEST_RELOAD_DELAY_MS (tests that show the main loop goes on meanwhile); 0 unset.
std::chrono::milliseconds test_reload_delay();

}  // namespace weedspray::daemon
