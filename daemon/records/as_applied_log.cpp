#include "daemon/records/as_applied_log.hpp"

#include <unistd.h>

#include <algorithm>
#include <ctime>
#include <stdexcept>
#include <system_error>
#include <vector>

namespace weedspray::daemon {

AsAppliedLog::AsAppliedLog(std::filesystem::path dir, std::uintmax_t rotate_bytes, int keep_files)
    : dir_(std::move(dir)), rotate_bytes_(rotate_bytes), keep_files_(keep_files) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw std::runtime_error(dir_.string() + ": " + ec.message());
}

AsAppliedLog::~AsAppliedLog() {
  if (file_ != nullptr) std::fclose(file_);
}

void AsAppliedLog::open_new(std::uint32_t nozzles) {
  if (file_ != nullptr) std::fclose(file_);
  // Wall-clock UTC in the name so files sort by creation; a sequence number breaks ties.
  char stamp[32];
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
  char name[64];
  std::snprintf(name, sizeof name, "as-applied-%s-%03u.csv", stamp, sequence_++ % 1000);
  path_ = dir_ / name;
  file_ = std::fopen(path_.c_str(), "w");
  if (file_ == nullptr) {
    ++write_errors_;
    return;
  }
  nozzles_ = nozzles;
  int n =
      std::fprintf(file_, "time_s,distance_m,speed_m_per_s,pressure_mpa,flow_l_per_min,volume_l");
  for (std::uint32_t i = 0; i < nozzles; ++i) n += std::fprintf(file_, ",duty_pct_%u", i);
  for (std::uint32_t i = 0; i < nozzles; ++i) n += std::fprintf(file_, ",density_%u", i);
  for (std::uint32_t i = 0; i < nozzles; ++i) n += std::fprintf(file_, ",crop_density_%u", i);
  n += std::fprintf(file_, "\n");
  bytes_ = static_cast<std::uintmax_t>(std::max(n, 0));
  prune();
}

void AsAppliedLog::prune() {
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir_, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("as-applied-") && name.ends_with(".csv")) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  while (files.size() > static_cast<std::size_t>(keep_files_)) {
    if (files.front() != path_) std::filesystem::remove(files.front(), ec);
    files.erase(files.begin());
  }
}

bool AsAppliedLog::write(const AppliedRecord& r) {
  if (file_ == nullptr || bytes_ >= rotate_bytes_ || r.nozzles != nozzles_) open_new(r.nozzles);
  if (file_ == nullptr) return false;
  int n = std::fprintf(file_, "%.4f,%.4f,%.3f,%.4f,%.4f,%.7f",
                       std::chrono::duration<double>(r.time).count(), r.distance_m, r.speed_m_per_s,
                       r.pressure_mpa, r.flow_l_per_min, r.volume_l);
  for (std::uint32_t i = 0; i < r.nozzles; ++i) n += std::fprintf(file_, ",%.1f", r.duty_pct[i]);
  for (std::uint32_t i = 0; i < r.nozzles; ++i) n += std::fprintf(file_, ",%.4f", r.density[i]);
  for (std::uint32_t i = 0; i < r.nozzles; ++i) {
    n += std::fprintf(file_, ",%.4f", r.crop_density[i]);
  }
  n += std::fprintf(file_, "\n");
  if (n <= 0 || std::ferror(file_)) {
    ++write_errors_;
    return false;
  }
  bytes_ += static_cast<std::uintmax_t>(n);
  return true;
}

void AsAppliedLog::flush() {
  if (file_ == nullptr) return;
  // fflush hands the lines to the kernel; fdatasync puts them on the card, so a power cut
  // loses at most the records since the last call (the writer calls this once a second).
  if (std::fflush(file_) != 0 || ::fdatasync(fileno(file_)) != 0) ++write_errors_;
}

}  // namespace weedspray::daemon
