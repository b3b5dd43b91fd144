// SPDX-License-Identifier: Apache-2.0
// How a raised or cleared alarm reaches the log: in the journal as one entry with the alarm's
// catalog MESSAGE_ID (journalctl -x prints its meaning and remedy) and its name and severity
// as fields; on a console as one line through spdlog, the remedy appended.
#pragma once

#include <string_view>

#include "daemon/supervision/alarms.hpp"

namespace weedspray::daemon {

// `detail`: what this occurrence measured (may be empty). Main thread only.
void log_alarm_raised(AlarmId id, std::string_view detail, bool to_journal);
// `why`: "cleared" by ClearAlarms, or why it cleared itself.
void log_alarm_cleared(AlarmId id, std::string_view why, bool to_journal);

}  // namespace weedspray::daemon
