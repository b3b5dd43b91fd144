// SPDX-License-Identifier: Apache-2.0
// Totals kept across restarts: ground covered, liquid sprayed, and what uniform spraying at the
// nominal dose would have used. Stored as a small TOML file, written atomically (temp + rename).
#pragma once

#include <cstdint>
#include <filesystem>

namespace weedspray::daemon {

// Where saved totals stand in the as-applied log: the seq of the last record handed to the log,
// and the volume the totals already held beyond it (records still queued for the writer). At
// start the log's records after `seq`, less `queued_l`, are the volume sprayed after the save
// (a crash or power cut loses up to the minute between saves): it is added back.
struct TotalsLogMark {
  bool known = false;  // false: saved without a mark, nothing to match
  std::uint64_t seq = 0;
  double queued_l = 0;
};

struct Totals {
  double area_m2 = 0;
  double volume_l = 0;
  double uniform_volume_l = 0;
  TotalsLogMark log;

  // 100 (1 - sprayed / uniform); 0 before anything was sprayed.
  double savings_pct() const noexcept;
};

// Missing file: zeros. A corrupt file: zeros and `error` set (the daemon logs it and goes on).
Totals load_totals(const std::filesystem::path& file, std::string* error = nullptr);
// Throws std::runtime_error naming the file.
void save_totals(const std::filesystem::path& file, const Totals& totals);

}  // namespace weedspray::daemon
