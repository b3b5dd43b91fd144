// SPDX-License-Identifier: Apache-2.0
// A simulated emergency-stop circuit, opened and closed by a test or a simulated operator. An
// opening runs the reaction at once on the thread that opens it, stamped with the clock's time,
// as the hardware backend's edge thread runs it at the edge. Closing counts at once (no
// bouncing contact to wait out).
#pragma once

#include <atomic>

#include "io/clock.hpp"
#include "io/estop_input.hpp"
#include "io/latest_value.hpp"

namespace weedspray::io::sim {

class ManualEstopInput final : public EstopInput {
 public:
  explicit ManualEstopInput(const Clock& clock, bool closed = true) noexcept : clock_(clock) {
    EstopSample s;
    s.circuit_closed = closed;
    s.time = clock.now();
    published_.publish(s);
  }

  EstopSample sample() const noexcept override { return published_.read(); }

  void arm(const EstopReaction& reaction) override {
    reaction_ = reaction;
    armed_.store(true);
    if (!published_.read().circuit_closed) run_reaction(clock_.now());
  }
  void disarm() noexcept override { armed_.store(false); }

  // One writer: the test or the simulated operator. Opening an open circuit does nothing.
  void set_closed(bool closed) noexcept {
    EstopSample s = published_.read();
    if (s.circuit_closed == closed) return;
    const auto now = clock_.now();
    s.circuit_closed = closed;
    s.time = now;
    if (!closed) ++s.openings;
    published_.publish(s);
    if (!closed) run_reaction(now);
  }

 private:
  void run_reaction(std::chrono::nanoseconds edge_time) noexcept {
    if (armed_.load() && reaction_.on_open != nullptr)
      reaction_.on_open(reaction_.context, edge_time);
  }

  const Clock& clock_;
  LatestValue<EstopSample> published_;
  EstopReaction reaction_;
  std::atomic<bool> armed_{false};
};

}  // namespace weedspray::io::sim
