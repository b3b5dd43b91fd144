// SPDX-License-Identifier: Apache-2.0
// The as-applied log: one CSV line per PWM period (time, distance, speed, pressure, flow, the
// volume sprayed since the previous line, per nozzle duty, weed density and crop density; then
// where it happened: UTC, the antenna's position and heading, the nozzle width, and per nozzle
// the position of its patch, its rate in L/ha and its ground speed; last the record's sequence
// number), in size-rotated files. README "Maps" lists the columns. Written by a normal-priority
// thread fed from the control loop's queue.
//
// Each line is formatted whole and appended in one write (LineAppender): a full disk or an I/O
// error never leaves a torn line. A line that cannot be written is held in memory (HeldLines)
// and retried in order by flush(), once a second, until it goes out; when the held lines pass
// their bound the newer ones are dropped and counted, and `seq` shows the gap. flush() also
// fdatasyncs: a power cut loses at most the last second (and the lines held in memory).
#pragma once

#include <cstdint>
#include <filesystem>
#include <mutex>
#include <string>

#include "daemon/records/held_lines.hpp"
#include "daemon/records/line_appender.hpp"
#include "daemon/records/map_geometry.hpp"
#include "daemon/sprayer/runtime_types.hpp"

namespace weedspray::daemon {

// How the machine's nozzles sit relative to its GNSS antenna (config [boom], [gnss]).
struct NozzlePlacement {
  double nozzle_width_m = 0.5;
  AntennaMount antenna;
};

// The bound on lines held while writes fail: about 10 minutes of 24 nozzles at the default 5
// records a second (1.35 kB each; 2.5 minutes at the highest, 20), time to free space in the
// field (export, delete old files); small beside the board's memory.
inline constexpr std::size_t kHeldLinesMaxBytes = 4 << 20;

// The records handed to the log by this run: the last one's seq and their summed volume.
struct AsAppliedProgress {
  std::uint64_t seq = 0;
  double volume_l = 0;
};

struct AsAppliedHealth {
  int error = 0;  // errno of the last failed write, open or fdatasync; 0 once writes work again
  std::size_t held_lines = 0;       // waiting in memory to be written
  std::uint64_t dropped_lines = 0;  // never written: the held lines were at their bound
  std::uint64_t write_errors = 0;   // failed writes, opens and fdatasyncs, retries included
};

class AsAppliedLog {
 public:
  // Creates `dir` if needed. Throws std::runtime_error naming the folder. `write_call` replaces
  // write(2) (tests simulate a full disk with it).
  AsAppliedLog(std::filesystem::path dir, std::uintmax_t rotate_bytes, int keep_files,
               NozzlePlacement placement = {}, std::size_t held_max_bytes = kHeldLinesMaxBytes,
               WriteCall write_call = nullptr);
  ~AsAppliedLog();
  AsAppliedLog(const AsAppliedLog&) = delete;
  AsAppliedLog& operator=(const AsAppliedLog&) = delete;

  // Formats one record (the next seq) and appends it behind any held lines; opens or rotates
  // the file as needed. Returns false when it was held or dropped instead of written.
  bool write(const AppliedRecord& record);
  // Writes the held lines in order (until one fails), then fdatasyncs. Call once a second.
  void flush();
  // Numbers the next record seq + 1 (the log's last at start, so seq runs on across runs).
  void continue_after(std::uint64_t seq);
  // Thread-safe: the totals read it from the main thread to mark where they stand in the log.
  AsAppliedProgress progress() const;
  const std::filesystem::path& current_file() const { return path_; }
  const std::filesystem::path& dir() const { return dir_; }
  AsAppliedHealth health() const;

 private:
  int append(std::uint32_t nozzles, std::string_view line);
  int open_new(std::uint32_t nozzles);
  void close_file();
  void prune();
  void failed(int error);
  void format_header(std::uint32_t nozzles);
  void format_record(const AppliedRecord& record);
  void format_position(const AppliedRecord& record);

  std::filesystem::path dir_;
  NozzlePlacement placement_;
  std::uintmax_t rotate_bytes_;
  int keep_files_;
  LineAppender appender_;
  HeldLines held_;
  std::filesystem::path path_;
  std::string header_;  // the open file's header line
  std::string line_;    // the record being formatted: its capacity is kept between records
  std::uint32_t nozzles_ = 0;
  std::uint64_t write_errors_ = 0;
  int error_ = 0;
  mutable std::mutex progress_mutex_;
  std::uint64_t next_seq_ = 1;  // guarded by progress_mutex_, with volume_l_
  double volume_l_ = 0;
  unsigned file_number_ = 0;
};

}  // namespace weedspray::daemon
