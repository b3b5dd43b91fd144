// SPDX-License-Identifier: Apache-2.0
// What each alarm means and what to do about it: one entry per alarm, the single source of the
// journal's message catalog (`journalctl -x`), the D-Bus AlarmDetails property, `sprayctl
// status` and docs/alarms.md.
#pragma once

#include <string>
#include <string_view>

#include "daemon/supervision/alarms.hpp"

namespace weedspray::daemon {

struct AlarmCatalogEntry {
  std::string_view message_id;  // the journal's MESSAGE_ID: 32 hex digits, fixed for good
  std::string_view meaning;     // what happened, one sentence
  std::string_view remedy;      // what the operator or the machine builder does next
};

const AlarmCatalogEntry& alarm_catalog_entry(AlarmId id) noexcept;
// "fault" (latches the Fault state: valves closed, pump off) or "warning".
std::string_view alarm_severity(AlarmId id) noexcept;

// The journal's catalog file (systemd's catalog format, journalctl --update-catalog).
std::string journal_catalog();
// The operator's table, docs/alarms.md.
std::string alarm_catalog_markdown();

}  // namespace weedspray::daemon
