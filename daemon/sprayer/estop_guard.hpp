// SPDX-License-Identifier: Apache-2.0
// The emergency stop's reaction and latch. The E-stop input (io/estop_input.hpp) runs
// on_open() on its edge thread at the circuit's first opening: the latch is set, the valves and
// the pump are written safe there and then, and the time from the edge to those writes is
// recorded. While latched, the valve thread holds the valves closed and the heartbeat low, and
// the pressure loop keeps the pump off and the return valve open. Only reset() (ClearAlarms)
// unlatches, and only once the circuit is closed again.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>

#include "io/clock.hpp"
#include "io/digital_output.hpp"
#include "io/estop_input.hpp"
#include "io/latest_value.hpp"

namespace weedspray::daemon {

struct EstopStatus {
  bool wired = false;          // an E-stop input exists
  bool circuit_closed = true;  // the input's debounced state (true when not wired)
  bool latched = false;        // outputs held safe until reset()
  std::uint64_t trips = 0;     // openings acted on since start
  // Edge -> valves and pump written safe: the latest trip's and the largest since start.
  std::chrono::nanoseconds last_reaction{0};
  std::chrono::nanoseconds max_reaction{0};
  std::uint64_t safe_write_errors = 0;  // safe writes refused during reactions
};

class EstopGuard {
 public:
  // `input`, `valves` and `pump` may be null (not wired).
  EstopGuard(const io::Clock& clock, io::EstopInput* input, io::DigitalOutputBank* valves,
             io::DigitalOutputBank* pump) noexcept
      : clock_(clock), input_(input), valves_(valves), pump_(pump) {}

  // What the input runs: io::EstopReaction{&EstopGuard::on_open, this}.
  io::EstopReaction reaction() noexcept { return {&EstopGuard::on_open, this}; }
  // The reaction: latch, write valves and pump safe, record the time. Real-time safe; one
  // thread at a time (the input's edge thread).
  void trip(std::chrono::nanoseconds edge_time) noexcept;

  // Read by the real-time loops at every cycle.
  const std::atomic<bool>& held() const noexcept { return held_; }
  // ClearAlarms: unlatches when the circuit is closed and no trip came meanwhile; false (still
  // latched) otherwise.
  bool reset() noexcept;
  EstopStatus status() const noexcept;

 private:
  static void on_open(void* self, std::chrono::nanoseconds edge_time) noexcept {
    static_cast<EstopGuard*>(self)->trip(edge_time);
  }

  const io::Clock& clock_;
  io::EstopInput* input_;
  io::DigitalOutputBank* valves_;
  io::DigitalOutputBank* pump_;
  std::atomic<std::uint64_t> trips_{0};
  std::atomic<bool> held_{false};
  EstopStatus reactions_;  // written by trip() only
  io::LatestValue<EstopStatus> published_;
};

}  // namespace weedspray::daemon
