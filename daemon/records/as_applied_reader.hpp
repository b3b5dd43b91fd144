// SPDX-License-Identifier: Apache-2.0
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
  std::uint64_t first_seq = 0;        // seq of the first and the last record (0: no seq column)
  std::uint64_t last_seq = 0;
};

// Every as-applied-*.csv in `dir`, in name (= creation) order. Throws std::runtime_error naming
// the folder when it cannot be listed.
std::vector<std::filesystem::path> as_applied_files(const std::filesystem::path& dir);
// One file. Throws std::runtime_error naming the file when it cannot be read or its header is
// not an as-applied header.
AsAppliedSummary read_as_applied_file(const std::filesystem::path& file);
// Every as-applied-*.csv in `dir`, in name (= creation) order.
AsAppliedSummary read_as_applied_dir(const std::filesystem::path& dir);
// The records numbered after `seq` (the seq column), read from the newest file back to the
// first that starts at or before it, so a start reads one or two files, not the folder. A file
// without the seq column ends the search.
AsAppliedSummary read_as_applied_after(const std::filesystem::path& dir, std::uint64_t seq);
// The seq of the newest record (0: none), from the newest file holding one.
std::uint64_t last_as_applied_seq(const std::filesystem::path& dir);

}  // namespace weedspray::daemon
