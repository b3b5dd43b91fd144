// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/as_applied_log.hpp"

#include <algorithm>
#include <array>
#include <cinttypes>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <ctime>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "daemon/sprayer/geometry.hpp"

namespace weedspray::daemon {
namespace {

// printf-style append: the fields keep the exact text they have always had (%.4f and the
// like), and `out` keeps its capacity, so a line costs no allocation once the first is written.
__attribute__((format(printf, 2, 3))) void appendf(std::string& out, const char* format, ...) {
  char field[400];  // a %.4f of any double fits
  std::va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(field, sizeof field, format, args);
  va_end(args);
  if (n > 0) out.append(field, std::min(static_cast<std::size_t>(n), sizeof field - 1));
}

}  // namespace

AsAppliedLog::AsAppliedLog(std::filesystem::path dir, std::uintmax_t rotate_bytes, int keep_files,
                           NozzlePlacement placement, std::size_t held_max_bytes,
                           WriteCall write_call)
    : dir_(std::move(dir)),
      placement_(placement),
      rotate_bytes_(rotate_bytes),
      keep_files_(keep_files),
      appender_(write_call),
      held_(held_max_bytes) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw std::runtime_error(dir_.string() + ": " + ec.message());
}

AsAppliedLog::~AsAppliedLog() {
  close_file();
}

void AsAppliedLog::close_file() {
  const bool empty = appender_.is_open() && appender_.size() == 0;
  appender_.close();
  // A file whose header could not be written holds nothing: readers would refuse it.
  std::error_code ec;
  if (empty) std::filesystem::remove(path_, ec);
}

void AsAppliedLog::format_header(std::uint32_t nozzles) {
  header_ = "time_s,distance_m,speed_m_per_s,pressure_mpa,flow_l_per_min,volume_l";
  for (std::uint32_t i = 0; i < nozzles; ++i) appendf(header_, ",duty_pct_%u", i);
  for (std::uint32_t i = 0; i < nozzles; ++i) appendf(header_, ",density_%u", i);
  for (std::uint32_t i = 0; i < nozzles; ++i) appendf(header_, ",crop_density_%u", i);
  // Appended after the columns of the first format, so scripts reading by position still work.
  header_ += ",utc,latitude_deg,longitude_deg,course_deg,nozzle_width_m";
  for (const char* name : {"latitude_deg", "longitude_deg", "rate_l_per_ha", "speed_m_per_s"}) {
    for (std::uint32_t i = 0; i < nozzles; ++i) appendf(header_, ",%s_%u", name, i);
  }
  header_ += ",seq\n";
}

int AsAppliedLog::open_new(std::uint32_t nozzles) {
  close_file();
  // Wall-clock UTC in the name so files sort by creation; a sequence number breaks ties.
  char stamp[32];
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
  // A new file every time: a restart within the same second must not append to the last run's.
  std::error_code ec;
  do {
    char name[64];
    std::snprintf(name, sizeof name, "as-applied-%s-%03u.csv", stamp, file_number_++ % 1000);
    path_ = dir_ / name;
  } while (std::filesystem::exists(path_, ec) && file_number_ % 1000 != 0);
  if (const int error = appender_.open(path_); error != 0) return error;
  nozzles_ = nozzles;
  format_header(nozzles);
  prune();
  return 0;
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

// One line into the current file (a new one when rotating or the nozzle count changed), its
// header first when the file is empty. Returns 0 or an errno; nothing partial stays behind.
int AsAppliedLog::append(std::uint32_t nozzles, std::string_view line) {
  if (!appender_.is_open() || appender_.size() >= rotate_bytes_ || nozzles != nozzles_) {
    if (const int error = open_new(nozzles); error != 0) return error;
  }
  if (appender_.size() == 0) {
    if (const int error = appender_.append(header_); error != 0) return error;
  }
  return appender_.append(line);
}

void AsAppliedLog::failed(int error) {
  error_ = error;
  ++write_errors_;
}

bool AsAppliedLog::write(const AppliedRecord& r) {
  format_record(r);
  // Behind held lines a record waits its turn: the file keeps the records' order.
  if (held_.empty()) {
    const int error = append(r.nozzles, line_);
    if (error == 0) {
      error_ = 0;
      return true;
    }
    failed(error);
  }
  held_.push(r.nozzles, line_);
  return false;
}

void AsAppliedLog::flush() {
  while (!held_.empty()) {
    const HeldLine& line = held_.front();
    if (const int error = append(line.nozzles, line.text); error != 0) {
      failed(error);
      return;
    }
    held_.pop();
  }
  // fdatasync puts the lines on the card, so a power cut loses at most the records since the
  // last call (the writer calls this once a second).
  if (const int error = appender_.sync(); error != 0) {
    failed(error);
    return;
  }
  if (appender_.is_open()) error_ = 0;
}

AsAppliedHealth AsAppliedLog::health() const {
  return {error_, held_.size(), held_.dropped(), write_errors_};
}

void AsAppliedLog::format_record(const AppliedRecord& r) {
  line_.clear();
  appendf(line_, "%.4f,%.4f,%.3f,%.4f,%.4f,%.7f", std::chrono::duration<double>(r.time).count(),
          r.distance_m, r.speed_m_per_s, r.pressure_mpa, r.flow_l_per_min, r.volume_l);
  for (std::uint32_t i = 0; i < r.nozzles; ++i) appendf(line_, ",%.1f", r.duty_pct[i]);
  for (std::uint32_t i = 0; i < r.nozzles; ++i) appendf(line_, ",%.4f", r.density[i]);
  for (std::uint32_t i = 0; i < r.nozzles; ++i) appendf(line_, ",%.4f", r.crop_density[i]);
  format_position(r);
  const std::lock_guard lock(progress_mutex_);
  volume_l_ += r.volume_l;
  appendf(line_, ",%" PRIu64 "\n", next_seq_++);
}

void AsAppliedLog::continue_after(std::uint64_t seq) {
  const std::lock_guard lock(progress_mutex_);
  next_seq_ = seq + 1;
}

AsAppliedProgress AsAppliedLog::progress() const {
  const std::lock_guard lock(progress_mutex_);
  return {next_seq_ - 1, volume_l_};
}

void AsAppliedLog::format_position(const AppliedRecord& r) {
  // The fix arrived at fix_time; the record is `time`: carry the antenna forward (or back) along
  // its course by the difference (at most the receiver's period, ~0.1-1 s).
  const double since_fix_s = std::chrono::duration<double>(r.time - r.fix_time).count();
  const std::optional<LatLon> antenna =
      r.fix_usable ? antenna_at(r.fix, since_fix_s) : std::optional<LatLon>();
  const double heading = r.fix.course_deg + r.yaw_rate_deg_per_s * since_fix_s;
  const bool placed = antenna.has_value() && std::isfinite(heading);
  line_ += ',';
  if (antenna.has_value() && r.fix.utc_ns != 0) {
    char utc[40];
    format_utc_ms(r.fix.utc_ns + static_cast<std::int64_t>(since_fix_s * 1e9), utc, sizeof utc);
    line_ += utc;
  }
  if (antenna.has_value()) {
    appendf(line_, ",%.8f,%.8f", antenna->latitude_deg, antenna->longitude_deg);
  } else {
    line_ += ",,";
  }
  if (placed) {
    appendf(line_, ",%.2f", std::fmod(std::fmod(heading, 360.0) + 360.0, 360.0));
  } else {
    line_ += ',';
  }
  appendf(line_, ",%.3f", placement_.nozzle_width_m);
  BoomSection boom{};
  boom.nozzles = static_cast<int>(r.nozzles);
  boom.nozzle_width_m = placement_.nozzle_width_m;
  std::array<LatLon, io::kMaxValves> patch{};
  for (std::uint32_t i = 0; placed && i < r.nozzles; ++i) {
    patch[i] = nozzle_patch(*antenna, heading, placement_.antenna, nozzle_right_offset_m(boom, i));
  }
  for (std::uint32_t i = 0; i < r.nozzles; ++i) {
    if (placed) {
      appendf(line_, ",%.8f", patch[i].latitude_deg);
    } else {
      line_ += ',';
    }
  }
  for (std::uint32_t i = 0; i < r.nozzles; ++i) {
    if (placed) {
      appendf(line_, ",%.8f", patch[i].longitude_deg);
    } else {
      line_ += ',';
    }
  }
  for (std::uint32_t i = 0; i < r.nozzles; ++i) {
    appendf(line_, ",%.1f",
            rate_l_per_ha(r.nozzle_flow_l_per_min[i], r.nozzle_speed_m_per_s[i],
                          placement_.nozzle_width_m));
  }
  for (std::uint32_t i = 0; i < r.nozzles; ++i) appendf(line_, ",%.3f", r.nozzle_speed_m_per_s[i]);
}

}  // namespace weedspray::daemon
