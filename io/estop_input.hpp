// SPDX-License-Identifier: Apache-2.0
// The emergency-stop input: a normally closed, monitored circuit. A closed circuit permits
// running; an open one (a pressed button, a cut wire, a lost pull resistor's supply) is a stop.
// The backend runs the reaction on the circuit's first opening edge, on its own thread, and
// publishes the contact's state for the rest of the daemon.
#pragma once

#include <chrono>
#include <cstdint>

namespace weedspray::io {

struct EstopSample {
  bool circuit_closed = false;      // closed, and held closed for the debounce time
  std::chrono::nanoseconds time{};  // when circuit_closed last changed
  std::uint64_t openings = 0;       // openings since start (each ran the reaction)
  std::uint64_t error_count = 0;    // failed reads of the input (each treated as an opening)
};

// What an opening runs: writes the outputs safe and latches the stop. Runs on the input's
// edge thread, so it must be real-time safe: no allocation, locks, logging or blocking.
struct EstopReaction {
  void (*on_open)(void* context, std::chrono::nanoseconds edge_time) noexcept = nullptr;
  void* context = nullptr;
};

class EstopInput {
 public:
  virtual ~EstopInput() = default;
  // Wait-free; safe from any thread.
  virtual EstopSample sample() const noexcept = 0;
  // Start-up: from now on `reaction` runs at every opening of the circuit, and at once when
  // the circuit is open already.
  virtual void arm(const EstopReaction& reaction) = 0;
  // Stops running the reaction (and the edge thread, where the backend has one).
  virtual void disarm() noexcept = 0;
};

// The contact's logic, without I/O. Opening acts on the first edge, undebounced: a contact
// that bounces open at all has been opened. Closing counts only once the circuit has stayed
// closed for `hold`, so a bouncing or intermittent contact keeps the stop.
class NormallyClosedContact {
 public:
  NormallyClosedContact(std::chrono::nanoseconds hold, bool closed,
                        std::chrono::nanoseconds now) noexcept
      : hold_(hold), raw_closed_(closed), closed_(closed), raw_since_(now), changed_at_(now) {}

  // A raw level seen at `time` (true: circuit closed). True when this edge opens the circuit.
  bool feed(bool closed, std::chrono::nanoseconds time) noexcept {
    if (closed == raw_closed_) return false;
    raw_closed_ = closed;
    raw_since_ = time;
    if (closed) return false;
    const bool was_closed = closed_;
    closed_ = false;
    if (was_closed) changed_at_ = time;
    return true;
  }
  // Re-evaluates at `now`: true when the circuit has just counted as closed again.
  bool settle(std::chrono::nanoseconds now) noexcept {
    if (closed_ || !raw_closed_ || now - raw_since_ < hold_) return false;
    closed_ = true;
    changed_at_ = now;
    return true;
  }
  bool closed() const noexcept { return closed_; }
  std::chrono::nanoseconds changed_at() const noexcept { return changed_at_; }
  // A closing waits for its hold time (for sleeping until pending_until()).
  bool pending() const noexcept { return raw_closed_ && !closed_; }
  std::chrono::nanoseconds pending_until() const noexcept { return raw_since_ + hold_; }

 private:
  std::chrono::nanoseconds hold_;
  bool raw_closed_;
  bool closed_;
  std::chrono::nanoseconds raw_since_;
  std::chrono::nanoseconds changed_at_;
};

}  // namespace weedspray::io
