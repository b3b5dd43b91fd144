// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/alarm_log.hpp"

#include <spdlog/spdlog.h>
#include <syslog.h>
#include <systemd/sd-journal.h>

#include <string>

#include "daemon/supervision/alarm_catalog.hpp"

namespace weedspray::daemon {
namespace {

// sd_journal_send takes printf-style fields: every value goes through "%s". Only a raised
// alarm carries the catalog's MESSAGE_ID (its text is the remedy); a clearing is told apart by
// WEEDSPRAY_ALARM_EVENT.
void send(int priority, const std::string& message, AlarmId id, const char* event) {
  const AlarmCatalogEntry& entry = alarm_catalog_entry(id);
  const std::string message_id =
      std::string_view(event) == "raised" ? std::string(entry.message_id) : std::string();
  const std::string name(alarm_name(id));
  const std::string severity(alarm_severity(id));
  const std::string remedy(entry.remedy);
  if (message_id.empty()) {
    sd_journal_send("MESSAGE=%s", message.c_str(), "PRIORITY=%d", priority, "SYSLOG_IDENTIFIER=%s",
                    "weedsprayd", "WEEDSPRAY_ALARM=%s", name.c_str(), "WEEDSPRAY_ALARM_EVENT=%s",
                    event, "WEEDSPRAY_SEVERITY=%s", severity.c_str(), nullptr);
    return;
  }
  sd_journal_send("MESSAGE=%s", message.c_str(), "PRIORITY=%d", priority, "MESSAGE_ID=%s",
                  message_id.c_str(), "SYSLOG_IDENTIFIER=%s", "weedsprayd", "WEEDSPRAY_ALARM=%s",
                  name.c_str(), "WEEDSPRAY_ALARM_EVENT=%s", event, "WEEDSPRAY_SEVERITY=%s",
                  severity.c_str(), "WEEDSPRAY_REMEDY=%s", remedy.c_str(), nullptr);
}

}  // namespace

void log_alarm_raised(AlarmId id, std::string_view detail, bool to_journal) {
  std::string message =
      "alarm raised: " + std::string(alarm_name(id)) + " (" + std::string(alarm_severity(id));
  if (is_fault(id)) message += ": valves closed, pump off";
  if (!detail.empty()) message += "; " + std::string(detail);
  message += ")";
  if (to_journal) {
    send(is_fault(id) ? LOG_ERR : LOG_WARNING, message, id, "raised");
    return;
  }
  const std::string line =
      message + " - what to do: " + std::string(alarm_catalog_entry(id).remedy);
  if (is_fault(id)) {
    spdlog::error("{}", line);
  } else {
    spdlog::warn("{}", line);
  }
}

void log_alarm_cleared(AlarmId id, std::string_view why, bool to_journal) {
  const std::string message =
      "alarm cleared: " + std::string(alarm_name(id)) + " (" + std::string(why) + ")";
  if (to_journal) {
    send(LOG_INFO, message, id, "cleared");
    return;
  }
  spdlog::info("{}", message);
}

}  // namespace weedspray::daemon
