// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/totals.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <sstream>
#include <string>
#include <system_error>

#include "daemon/records/atomic_file.hpp"

namespace weedspray::daemon {

double Totals::savings_pct() const noexcept {
  if (uniform_volume_l <= 0) return 0;
  return 100.0 * (1.0 - volume_l / uniform_volume_l);
}

Totals load_totals(const std::filesystem::path& file, std::string* error) {
  Totals totals;
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return totals;
  try {
    const toml::table table = toml::parse_file(file.string());
    totals.area_m2 = table["area_m2"].value_or(0.0);
    totals.volume_l = table["volume_l"].value_or(0.0);
    totals.uniform_volume_l = table["uniform_volume_l"].value_or(0.0);
    totals.log.known = table.contains("log_seq");
    totals.log.seq = static_cast<std::uint64_t>(
        std::max<std::int64_t>(0, table["log_seq"].value_or(std::int64_t{0})));
    totals.log.queued_l = table["log_queued_l"].value_or(0.0);
  } catch (const toml::parse_error& e) {
    if (error != nullptr) {
      *error = file.string() + ":" + std::to_string(e.source().begin.line) + ": " +
               std::string(e.description());
    }
    return Totals{};
  }
  return totals;
}

void save_totals(const std::filesystem::path& file, const Totals& totals) {
  toml::table table{{"area_m2", totals.area_m2},
                    {"volume_l", totals.volume_l},
                    {"uniform_volume_l", totals.uniform_volume_l}};
  if (totals.log.known) {
    table.insert("log_seq", static_cast<std::int64_t>(totals.log.seq));
    table.insert("log_queued_l", totals.log.queued_l);
  }
  std::ostringstream text;
  text << table << "\n";
  write_file_atomically(file, text.str());
}

}  // namespace weedspray::daemon
