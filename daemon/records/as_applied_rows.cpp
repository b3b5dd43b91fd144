// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/as_applied_rows.hpp"

#include <algorithm>
#include <charconv>
#include <stdexcept>

namespace weedspray::daemon {
namespace {

void split(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma == std::string_view::npos ? comma : comma - start));
    if (comma == std::string_view::npos) return;
    start = comma + 1;
  }
}

bool number(std::string_view text, double& out) {
  if (text.empty()) return false;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && end == text.data() + text.size();
}

// Per-nozzle columns NAME_0 .. NAME_{n-1}, consecutive: the first one's index.
bool read_block(const std::vector<std::string_view>& fields, std::size_t first, std::size_t n,
                std::vector<double>& out) {
  out.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!number(fields[first + i], out[i])) return false;
  }
  return true;
}

}  // namespace

std::size_t AsAppliedRows::column(std::string_view name) const {
  return static_cast<std::size_t>(std::find(header_.begin(), header_.end(), name) -
                                  header_.begin());
}

AsAppliedRows::AsAppliedRows(const std::filesystem::path& file) : file_(file) {
  in_.open(file, std::ios::binary);
  if (!in_) throw std::runtime_error(file.string() + ": cannot be read");
  std::string header_line;
  if (!std::getline(in_, header_line) || in_.eof())
    throw std::runtime_error(file.string() + ": not an as-applied log (no header line)");
  std::vector<std::string_view> names;
  split(header_line, names);
  for (const auto name : names) header_.emplace_back(name);
  while (column("duty_pct_" + std::to_string(nozzles_)) < header_.size()) ++nozzles_;
  time_col_ = column("time_s");
  speed_col_ = column("speed_m_per_s");
  duty_col_ = column("duty_pct_0");
  density_col_ = column("density_0");
  crop_col_ = column("crop_density_0");
  if (time_col_ >= header_.size() || speed_col_ >= header_.size() || nozzles_ == 0 ||
      density_col_ >= header_.size() || crop_col_ >= header_.size())
    throw std::runtime_error(file.string() +
                             ": not an as-applied log (header lacks time_s, speed_m_per_s or "
                             "the per-nozzle duty_pct_N/density_N/crop_density_N)");
  utc_col_ = column("utc");
  lat_col_ = column("latitude_deg");
  lon_col_ = column("longitude_deg");
  course_col_ = column("course_deg");
  width_col_ = column("nozzle_width_m");
  nozzle_lat_col_ = column("latitude_deg_0");
  nozzle_lon_col_ = column("longitude_deg_0");
  rate_col_ = column("rate_l_per_ha_0");
  nozzle_speed_col_ = column("speed_m_per_s_0");
  map_columns_ = true;
  for (const std::size_t c : {utc_col_, lat_col_, lon_col_, course_col_, width_col_,
                              nozzle_lat_col_, nozzle_lon_col_, rate_col_, nozzle_speed_col_}) {
    map_columns_ = map_columns_ && c < header_.size();
  }
  for (const std::size_t first : {duty_col_, density_col_, crop_col_}) {
    if (first + nozzles_ > header_.size())
      throw std::runtime_error(file.string() + ": per-nozzle columns cut short in the header");
  }
}

bool AsAppliedRows::next(AsAppliedRow& row) {
  while (std::getline(in_, line_)) {
    // getline stops at the end of the file without a newline: that line was cut mid-write.
    const bool cut = in_.eof();
    if (!cut && parse(row)) return true;
    ++((cut || in_.peek() == std::char_traits<char>::eof()) ? torn_tail_lines_ : damaged_lines_);
  }
  return false;
}

bool AsAppliedRows::parse(AsAppliedRow& r) {
  split(line_, fields_);
  if (fields_.size() != header_.size()) return false;
  if (!number(fields_[time_col_], r.time_s) || !number(fields_[speed_col_], r.speed_m_per_s) ||
      !read_block(fields_, duty_col_, nozzles_, r.duty_pct) ||
      !read_block(fields_, density_col_, nozzles_, r.density) ||
      !read_block(fields_, crop_col_, nozzles_, r.crop_density))
    return false;
  r.utc_ns = 0;
  r.has_position = false;
  r.nozzles_placed = false;
  if (!map_columns_) {
    // The first format: no rates or nozzle speeds either; the rows carry no position.
    r.rate_l_per_ha.assign(nozzles_, 0.0);
    r.nozzle_speed_m_per_s.assign(nozzles_, r.speed_m_per_s);
    return true;
  }
  if (!number(fields_[width_col_], r.nozzle_width_m) ||
      !read_block(fields_, rate_col_, nozzles_, r.rate_l_per_ha) ||
      !read_block(fields_, nozzle_speed_col_, nozzles_, r.nozzle_speed_m_per_s))
    return false;
  if (!fields_[utc_col_].empty()) {
    const std::optional<std::int64_t> utc = parse_utc(fields_[utc_col_]);
    if (!utc) return false;
    r.utc_ns = *utc;
  }
  if (fields_[lat_col_].empty()) return true;
  if (!number(fields_[lat_col_], r.antenna.latitude_deg) ||
      !number(fields_[lon_col_], r.antenna.longitude_deg))
    return false;
  r.has_position = true;
  if (fields_[course_col_].empty() || fields_[nozzle_lat_col_].empty()) return true;
  if (!number(fields_[course_col_], r.course_deg)) return false;
  r.patch.resize(nozzles_);
  for (std::size_t i = 0; i < nozzles_; ++i) {
    if (!number(fields_[nozzle_lat_col_ + i], r.patch[i].latitude_deg) ||
        !number(fields_[nozzle_lon_col_ + i], r.patch[i].longitude_deg))
      return false;
  }
  r.nozzles_placed = true;
  return true;
}

}  // namespace weedspray::daemon
