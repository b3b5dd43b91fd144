// SPDX-License-Identifier: Apache-2.0
// spdlog set-up: the journal when started by systemd (JOURNAL_STREAM / INVOCATION_ID set),
// the console otherwise. Only the main thread and workers log; real-time loops never do.
#pragma once

#include <string>

namespace weedspray::daemon {

void setup_logging(const std::string& level);
void set_log_level(const std::string& level);
// Whether setup_logging chose the journal (structured entries may then be sent directly).
bool logs_to_journal() noexcept;

}  // namespace weedspray::daemon
