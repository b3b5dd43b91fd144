// Reads the as-applied CSV files back (the soak's reconciliation, a user's scripts): every
// complete record is counted and its volume summed. A crash or power cut can leave the last
// line of the newest file torn (cut mid-line: no newline, or fewer fields than the header);
// such a line is skipped and counted, never an error. A torn line anywhere else is damage and
// is counted separately.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace weedspray::daemon {

struct AsAppliedSummary {
  std::size_t files = 0;
  std::uint64_t records = 0;
  double volume_l = 0;      // sum of the records' volume_l column
  double first_time_s = 0;  // time_s of the first record, last record
  double last_time_s = 0;
  std::uint64_t torn_tail_lines = 0;  // a cut last line of a file (tolerated)
  std::uint64_t damaged_lines = 0;    // malformed lines elsewhere
};

// One file. Throws std::runtime_error naming the file when it cannot be read or its header is
// not an as-applied header.
AsAppliedSummary read_as_applied_file(const std::filesystem::path& file);
// Every as-applied-*.csv in `dir`, in name (= creation) order.
AsAppliedSummary read_as_applied_dir(const std::filesystem::path& dir);

}  // namespace weedspray::daemon
