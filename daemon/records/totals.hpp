// Totals kept across restarts: ground covered, liquid sprayed, and what uniform spraying at the
// nominal dose would have used. Stored as a small TOML file, written atomically (temp + rename).
#pragma once

#include <filesystem>

namespace weedspray::daemon {

struct Totals {
  double area_m2 = 0;
  double volume_l = 0;
  double uniform_volume_l = 0;

  // 100 (1 - sprayed / uniform); 0 before anything was sprayed.
  double savings_pct() const noexcept;
};

// Missing file: zeros. A corrupt file: zeros and `error` set (the daemon logs it and goes on).
Totals load_totals(const std::filesystem::path& file, std::string* error = nullptr);
// Throws std::runtime_error naming the file.
void save_totals(const std::filesystem::path& file, const Totals& totals);

}  // namespace weedspray::daemon
