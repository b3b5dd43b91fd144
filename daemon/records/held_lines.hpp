// SPDX-License-Identifier: Apache-2.0
// Formatted as-applied lines that could not be written yet (a full disk, an I/O error), kept in
// order in memory to be retried, up to a byte bound; a line past the bound is dropped and
// counted (its seq number is then missing from the file).
#pragma once

#include <cstdint>
#include <deque>
#include <string>
#include <string_view>

namespace weedspray::daemon {

struct HeldLine {
  std::uint32_t nozzles = 0;  // the header it belongs under
  std::string text;           // one whole line, '\n' included
};

class HeldLines {
 public:
  explicit HeldLines(std::size_t max_bytes) : max_bytes_(max_bytes) {}

  // Keeps the line behind the others, or drops it (false) when it would pass the bound.
  bool push(std::uint32_t nozzles, std::string_view text);
  const HeldLine& front() const { return lines_.front(); }
  void pop();
  bool empty() const { return lines_.empty(); }
  std::size_t size() const { return lines_.size(); }
  std::size_t bytes() const { return bytes_; }
  std::uint64_t dropped() const { return dropped_; }

 private:
  std::size_t max_bytes_;
  std::size_t bytes_ = 0;
  std::uint64_t dropped_ = 0;
  std::deque<HeldLine> lines_;
};

}  // namespace weedspray::daemon
