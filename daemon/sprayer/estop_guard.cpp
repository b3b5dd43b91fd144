// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/estop_guard.hpp"

namespace weedspray::daemon {

void EstopGuard::trip(std::chrono::nanoseconds edge_time) noexcept {
  // Counted before the latch is set: reset() sees the count move whenever its unlatching may
  // have raced this latch.
  trips_.fetch_add(1);
  held_.store(true);
  if (valves_ != nullptr && valves_->force_safe() != 0) ++reactions_.safe_write_errors;
  if (pump_ != nullptr && pump_->force_safe() != 0) ++reactions_.safe_write_errors;
  const std::chrono::nanoseconds reaction = clock_.now() - edge_time;
  ++reactions_.trips;
  reactions_.last_reaction = reaction;
  if (reaction > reactions_.max_reaction) reactions_.max_reaction = reaction;
  published_.publish(reactions_);
}

bool EstopGuard::reset() noexcept {
  const std::uint64_t trips = trips_.load();
  if (input_ != nullptr && !input_->sample().circuit_closed) return false;
  held_.store(false);
  if (trips_.load() == trips) return true;
  held_.store(true);  // an opening came in between: it stands
  return false;
}

EstopStatus EstopGuard::status() const noexcept {
  EstopStatus s = published_.read();
  s.wired = input_ != nullptr;
  s.circuit_closed = input_ == nullptr || input_->sample().circuit_closed;
  s.latched = held_.load();
  return s;
}

}  // namespace weedspray::daemon
