#include "daemon/records/as_applied_log.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <ctime>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "daemon/sprayer/geometry.hpp"

namespace weedspray::daemon {

AsAppliedLog::AsAppliedLog(std::filesystem::path dir, std::uintmax_t rotate_bytes, int keep_files,
                           NozzlePlacement placement)
    : dir_(std::move(dir)),
      placement_(placement),
      rotate_bytes_(rotate_bytes),
      keep_files_(keep_files) {
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
  // Appended after the columns of the first format, so scripts reading by position still work.
  n += std::fprintf(file_, ",utc,latitude_deg,longitude_deg,course_deg,nozzle_width_m");
  for (const char* name : {"latitude_deg", "longitude_deg", "rate_l_per_ha", "speed_m_per_s"}) {
    for (std::uint32_t i = 0; i < nozzles; ++i) n += std::fprintf(file_, ",%s_%u", name, i);
  }
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
  n += write_position(r);
  n += std::fprintf(file_, "\n");
  if (n <= 0 || std::ferror(file_)) {
    ++write_errors_;
    return false;
  }
  bytes_ += static_cast<std::uintmax_t>(n);
  return true;
}

int AsAppliedLog::write_position(const AppliedRecord& r) {
  // The fix arrived at fix_time; the record is `time`: carry the antenna forward (or back) along
  // its course by the difference (at most the receiver's period, ~0.1-1 s).
  const double since_fix_s = std::chrono::duration<double>(r.time - r.fix_time).count();
  const std::optional<LatLon> antenna =
      r.fix_usable ? antenna_at(r.fix, since_fix_s) : std::optional<LatLon>();
  const double heading = r.fix.course_deg + r.yaw_rate_deg_per_s * since_fix_s;
  const bool placed = antenna.has_value() && std::isfinite(heading);
  int n = 0;
  if (antenna.has_value() && r.fix.utc_ns != 0) {
    char utc[40];
    format_utc_ms(r.fix.utc_ns + static_cast<std::int64_t>(since_fix_s * 1e9), utc, sizeof utc);
    n += std::fprintf(file_, ",%s", utc);
  } else {
    n += std::fprintf(file_, ",");
  }
  if (antenna.has_value()) {
    n += std::fprintf(file_, ",%.8f,%.8f", antenna->latitude_deg, antenna->longitude_deg);
  } else {
    n += std::fprintf(file_, ",,");
  }
  if (placed) {
    n += std::fprintf(file_, ",%.2f", std::fmod(std::fmod(heading, 360.0) + 360.0, 360.0));
  } else {
    n += std::fprintf(file_, ",");
  }
  n += std::fprintf(file_, ",%.3f", placement_.nozzle_width_m);
  BoomSection boom{};
  boom.nozzles = static_cast<int>(r.nozzles);
  boom.nozzle_width_m = placement_.nozzle_width_m;
  std::array<LatLon, io::kMaxValves> patch{};
  for (std::uint32_t i = 0; placed && i < r.nozzles; ++i) {
    patch[i] = nozzle_patch(*antenna, heading, placement_.antenna, nozzle_right_offset_m(boom, i));
  }
  for (std::uint32_t i = 0; i < r.nozzles; ++i) {
    n += placed ? std::fprintf(file_, ",%.8f", patch[i].latitude_deg) : std::fprintf(file_, ",");
  }
  for (std::uint32_t i = 0; i < r.nozzles; ++i) {
    n += placed ? std::fprintf(file_, ",%.8f", patch[i].longitude_deg) : std::fprintf(file_, ",");
  }
  for (std::uint32_t i = 0; i < r.nozzles; ++i) {
    n += std::fprintf(file_, ",%.1f",
                      rate_l_per_ha(r.nozzle_flow_l_per_min[i], r.nozzle_speed_m_per_s[i],
                                    placement_.nozzle_width_m));
  }
  for (std::uint32_t i = 0; i < r.nozzles; ++i) {
    n += std::fprintf(file_, ",%.3f", r.nozzle_speed_m_per_s[i]);
  }
  return n;
}

void AsAppliedLog::flush() {
  if (file_ == nullptr) return;
  // fflush hands the lines to the kernel; fdatasync puts them on the card, so a power cut
  // loses at most the records since the last call (the writer calls this once a second).
  if (std::fflush(file_) != 0 || ::fdatasync(fileno(file_)) != 0) ++write_errors_;
}

}  // namespace weedspray::daemon
