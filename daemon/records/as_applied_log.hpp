// The as-applied log: one CSV line per PWM period (time, distance, speed, pressure, flow, the
// volume sprayed since the previous line, per nozzle duty, weed density and crop density; then
// where it happened: UTC, the antenna's position and heading, the nozzle width, and per nozzle
// the position of its patch, its rate in L/ha and its ground speed), in size-rotated files.
// README "Maps" lists the columns. Written by a normal-priority thread fed from the control
// loop's queue; flushed and fdatasync'd every second (a power cut loses at most that second; a
// reader must tolerate a torn last line).
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>

#include "daemon/records/map_geometry.hpp"
#include "daemon/sprayer/runtime_types.hpp"

namespace weedspray::daemon {

// How the machine's nozzles sit relative to its GNSS antenna (config [boom], [gnss]).
struct NozzlePlacement {
  double nozzle_width_m = 0.5;
  AntennaMount antenna;
};

class AsAppliedLog {
 public:
  // Creates `dir` if needed. Throws std::runtime_error naming the folder.
  AsAppliedLog(std::filesystem::path dir, std::uintmax_t rotate_bytes, int keep_files,
               NozzlePlacement placement = {});
  ~AsAppliedLog();
  AsAppliedLog(const AsAppliedLog&) = delete;
  AsAppliedLog& operator=(const AsAppliedLog&) = delete;

  // Appends one record; opens or rotates the file as needed. Returns false on a write error.
  bool write(const AppliedRecord& record);
  void flush();
  const std::filesystem::path& current_file() const { return path_; }
  std::uint64_t write_errors() const { return write_errors_; }

 private:
  void open_new(std::uint32_t nozzles);
  void prune();

  int write_position(const AppliedRecord& record);

  std::filesystem::path dir_;
  NozzlePlacement placement_;
  std::uintmax_t rotate_bytes_;
  int keep_files_;
  std::FILE* file_ = nullptr;
  std::filesystem::path path_;
  std::uintmax_t bytes_ = 0;
  std::uint32_t nozzles_ = 0;
  std::uint64_t write_errors_ = 0;
  unsigned sequence_ = 0;
};

}  // namespace weedspray::daemon
