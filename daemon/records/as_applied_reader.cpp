// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/as_applied_reader.hpp"

#include <algorithm>
#include <charconv>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace weedspray::daemon {
namespace {

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma == std::string_view::npos ? comma : comma - start));
    if (comma == std::string_view::npos) return fields;
    start = comma + 1;
  }
}

bool parse_double(std::string_view text, double& out) {
  if (text.empty()) return false;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && end == text.data() + text.size();
}

bool parse_seq(std::string_view text, std::uint64_t& out) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return !text.empty() && ec == std::errc() && end == text.data() + text.size();
}

void merge(AsAppliedSummary& into, const AsAppliedSummary& file) {
  if (file.records > 0) {
    if (into.records == 0) {
      into.first_time_s = file.first_time_s;
      into.first_seq = file.first_seq;
    }
    into.last_time_s = file.last_time_s;
    into.last_seq = file.last_seq;
  }
  into.files += file.files;
  into.records += file.records;
  into.volume_l += file.volume_l;
  into.torn_tail_lines += file.torn_tail_lines;
  into.damaged_lines += file.damaged_lines;
}

// `after_seq`: only records numbered after it count (0: every record).
AsAppliedSummary read_file_after(const std::filesystem::path& file, std::uint64_t after_seq) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file.string() + ": cannot be read");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  AsAppliedSummary summary;
  summary.files = 1;
  if (text.empty()) return summary;  // created, then a crash before its header went out
  std::size_t line_start = text.find('\n');
  const std::vector<std::string_view> header =
      split(std::string_view(text).substr(0, line_start == std::string::npos ? 0 : line_start));
  const auto column = [&](std::string_view name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const std::size_t time_col = column("time_s");
  const std::size_t volume_col = column("volume_l");
  const std::size_t seq_col = column("seq");
  if (line_start == std::string::npos || time_col >= header.size() || volume_col >= header.size())
    throw std::runtime_error(file.string() +
                             ": not an as-applied log (header lacks time_s/volume_l)");
  ++line_start;
  while (line_start < text.size()) {
    const std::size_t end = text.find('\n', line_start);
    const bool last = end == std::string::npos || end + 1 >= text.size();
    const std::string_view line = std::string_view(text).substr(
        line_start, end == std::string::npos ? end : end - line_start);
    line_start = end == std::string::npos ? text.size() : end + 1;
    const std::vector<std::string_view> fields = split(line);
    double time_s = 0;
    double volume_l = 0;
    const bool whole = end != std::string::npos && fields.size() == header.size() &&
                       parse_double(fields[time_col], time_s) &&
                       parse_double(fields[volume_col], volume_l);
    if (!whole) {
      ++(last ? summary.torn_tail_lines : summary.damaged_lines);
      continue;
    }
    std::uint64_t seq = 0;
    if (seq_col < header.size() && !parse_seq(fields[seq_col], seq)) {
      ++(last ? summary.torn_tail_lines : summary.damaged_lines);
      continue;
    }
    if (after_seq != 0 && seq <= after_seq) continue;
    if (summary.records == 0) {
      summary.first_time_s = time_s;
      summary.first_seq = seq;
    }
    summary.last_time_s = time_s;
    summary.last_seq = seq;
    ++summary.records;
    summary.volume_l += volume_l;
  }
  return summary;
}

}  // namespace

AsAppliedSummary read_as_applied_file(const std::filesystem::path& file) {
  return read_file_after(file, 0);
}

std::vector<std::filesystem::path> as_applied_files(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("as-applied-") && name.ends_with(".csv")) files.push_back(entry.path());
  }
  if (ec) throw std::runtime_error(dir.string() + ": " + ec.message());
  std::sort(files.begin(), files.end());
  return files;
}

AsAppliedSummary read_as_applied_dir(const std::filesystem::path& dir) {
  AsAppliedSummary summary;
  for (const auto& file : as_applied_files(dir)) merge(summary, read_as_applied_file(file));
  return summary;
}

AsAppliedSummary read_as_applied_after(const std::filesystem::path& dir, std::uint64_t seq) {
  const std::vector<std::filesystem::path> files = as_applied_files(dir);
  std::vector<AsAppliedSummary> newest_first;
  for (auto file = files.rbegin(); file != files.rend(); ++file) {
    const AsAppliedSummary whole = read_file_after(*file, 0);
    if (whole.records > 0 && whole.last_seq == 0) break;  // written before the seq column
    newest_first.push_back(whole.first_seq > seq ? whole : read_file_after(*file, seq));
    if (whole.records > 0 && whole.first_seq <= seq) break;
  }
  AsAppliedSummary summary;
  for (auto file = newest_first.rbegin(); file != newest_first.rend(); ++file)
    merge(summary, *file);
  return summary;
}

std::uint64_t last_as_applied_seq(const std::filesystem::path& dir) {
  const std::vector<std::filesystem::path> files = as_applied_files(dir);
  for (auto file = files.rbegin(); file != files.rend(); ++file) {
    const AsAppliedSummary summary = read_file_after(*file, 0);
    if (summary.records > 0) return summary.last_seq;
  }
  return 0;
}

}  // namespace weedspray::daemon
