// SPDX-License-Identifier: Apache-2.0
#include "daemon/logging.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/sinks/systemd_sink.h>
#include <spdlog/spdlog.h>

#include <cstdlib>

namespace weedspray::daemon {
namespace {
bool g_to_journal = false;
}  // namespace

bool logs_to_journal() noexcept {
  return g_to_journal;
}

void setup_logging(const std::string& level) {
  const bool under_systemd =
      std::getenv("JOURNAL_STREAM") != nullptr || std::getenv("INVOCATION_ID") != nullptr;
  g_to_journal = under_systemd;
  std::shared_ptr<spdlog::logger> logger;
  if (under_systemd) {
    logger = std::make_shared<spdlog::logger>(
        "weedsprayd", std::make_shared<spdlog::sinks::systemd_sink_mt>("weedsprayd"));
    logger->set_pattern("%v");  // the journal adds time, level and unit
  } else {
    logger = std::make_shared<spdlog::logger>(
        "weedsprayd", std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
  }
  spdlog::set_default_logger(logger);
  set_log_level(level);
}

void set_log_level(const std::string& level) {
  spdlog::set_level(spdlog::level::from_str(level));
  spdlog::flush_on(spdlog::level::info);
}

}  // namespace weedspray::daemon
