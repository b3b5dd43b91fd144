// SPDX-License-Identifier: Apache-2.0
// The daemon's valves keep their stagger slots: the PWM driver starts a closed valve at once
// (immediate mode, so spray lands on the imaged ground), and valves that start together — at
// Start, or at the end of a weed-free stretch — must still fall back into their own phases, or
// the boom pulses synchronously (pressure ripple, and a line meter that cannot tell the nozzles
// apart). Judged from every write the valve thread makes, on the simulated machine.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <set>

#include "daemon/backends/backends.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "tests/sim/daemon/run_until.hpp"
#include "tests/sim/daemon/spraying_machine.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

// Forwards to the real valves and records each changed mask with the clock's time, into a
// fixed array (the valve thread must not allocate).
class RecordingBank final : public io::DigitalOutputBank {
 public:
  RecordingBank(io::DigitalOutputBank& inner, const io::Clock& clock)
      : inner_(inner), clock_(clock) {}
  std::size_t size() const noexcept override { return inner_.size(); }
  int write(std::uint32_t mask) noexcept override {
    if (mask != last_) {
      const std::size_t n = count_.load(std::memory_order_relaxed);
      if (n < edges_.size()) {
        edges_[n] = {clock_.now(), mask};
        count_.store(n + 1, std::memory_order_release);
      }
      last_ = mask;
    }
    return inner_.write(mask);
  }
  int force_safe() noexcept override { return inner_.force_safe(); }
  std::uint32_t safe_mask() const noexcept override { return inner_.safe_mask(); }

  struct Edge {
    std::chrono::nanoseconds time{};
    std::uint32_t mask = 0;
  };
  std::size_t count() const noexcept { return count_.load(std::memory_order_acquire); }
  const Edge& edge(std::size_t i) const noexcept { return edges_[i]; }

 private:
  io::DigitalOutputBank& inner_;
  const io::Clock& clock_;
  std::uint32_t last_ = 0xffffffffu;
  std::array<Edge, 20000> edges_{};
  std::atomic<std::size_t> count_{0};
};

TEST(Stagger, ValvesStartedTogetherOpenInTheirOwnPhases) {
  SprayingMachine m;
  RecordingBank valves(*m.backends.valves, *m.backends.clock);
  m.backends.valves = &valves;
  m.start();
  const auto began = m.backends.clock->now();
  run_until(
      m.backends, [] { return false; }, 6s);
  m.sprayer->stop();

  // Opening edges per valve after the first 2 s, as phases within the PWM period.
  const auto period = std::chrono::nanoseconds(std::llround(1e9 / m.config.pwm.frequency_hz));
  const std::size_t nozzles = static_cast<std::size_t>(m.config.boom.nozzles);
  std::vector<std::multiset<long>> phases_ms(nozzles);
  for (std::size_t i = 1; i < valves.count(); ++i) {
    const auto& before = valves.edge(i - 1);
    const auto& edge = valves.edge(i);
    if (edge.time - began < 2s) continue;
    for (std::size_t v = 0; v < nozzles; ++v)
      if (!(before.mask >> v & 1u) && (edge.mask >> v & 1u))
        phases_ms[v].insert(static_cast<long>((edge.time % period) / 10ms));  // 10 ms bins
  }
  // Each spraying valve's openings sit in one phase bin (or two adjacent, at a bin edge); the
  // valves' bins differ from one another.
  std::set<long> valve_phases;
  std::size_t spraying = 0;
  for (std::size_t v = 0; v < nozzles; ++v) {
    if (phases_ms[v].size() < 5) continue;  // this valve hardly sprayed
    ++spraying;
    long most = 0, bin = -1;
    for (long b : phases_ms[v])
      if (static_cast<long>(phases_ms[v].count(b)) > most) most = phases_ms[v].count(b), bin = b;
    valve_phases.insert(bin);
  }
  ASSERT_GE(spraying, 3U) << "too few valves sprayed to judge the phases";
  EXPECT_EQ(valve_phases.size(), spraying)
      << "valves that spray open in the same phase: the PWM is synchronous";
}

}  // namespace
}  // namespace weedspray::daemon
