// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/held_lines.hpp"

namespace weedspray::daemon {

bool HeldLines::push(std::uint32_t nozzles, std::string_view text) {
  if (bytes_ + text.size() > max_bytes_) {
    ++dropped_;
    return false;
  }
  lines_.push_back(HeldLine{nozzles, std::string(text)});
  bytes_ += text.size();
  return true;
}

void HeldLines::pop() {
  bytes_ -= lines_.front().text.size();
  lines_.pop_front();
}

}  // namespace weedspray::daemon
