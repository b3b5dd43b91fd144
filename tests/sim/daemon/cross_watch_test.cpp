// SPDX-License-Identifier: Apache-2.0
// The loops' cross-watch on the simulated machine: when the pressure loop stalls (stuck inside
// an output write), the valve thread switches the pump off; when the valve thread stalls, the
// pressure loop switches the pump off and opens the return valve. Each stall is made by an
// output wrapper that blocks only the thread it is meant to stall.
#include <pthread.h>

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <string>
#include <thread>

#include "daemon/backends/backends.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "tests/sim/daemon/run_until.hpp"
#include "tests/sim/daemon/spraying_machine.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

bool on_thread(const char* name) {
  char current[16] = {};
  pthread_getname_np(pthread_self(), current, sizeof current);
  return std::strcmp(current, name) == 0;
}

// Forwards to the real output, except that calls from thread `stalled_thread` block while
// `stall` is set (without reaching the output).
class StallingBank final : public io::DigitalOutputBank {
 public:
  StallingBank(io::DigitalOutputBank& inner, const char* stalled_thread)
      : inner_(inner), stalled_thread_(stalled_thread) {}
  std::size_t size() const noexcept override { return inner_.size(); }
  int write(std::uint32_t mask) noexcept override {
    if (block()) return 0;
    return inner_.write(mask);
  }
  int force_safe() noexcept override {
    if (block()) return 0;
    return inner_.force_safe();
  }
  std::uint32_t safe_mask() const noexcept override { return inner_.safe_mask(); }
  std::atomic<bool> stall{false};
  std::atomic<bool> stalled_once{false};

 private:
  bool block() noexcept {
    if (!stall.load() || !on_thread(stalled_thread_)) return false;
    stalled_once = true;
    while (stall.load()) std::this_thread::sleep_for(1ms);
    return true;
  }
  io::DigitalOutputBank& inner_;
  const char* stalled_thread_;
};

TEST(CrossWatch, AStalledPressureLoopHasItsPumpSwitchedOffByTheValveThread) {
  SprayingMachine m;
  StallingBank pump(*m.backends.pump, "ws-pressure");
  m.backends.pump = &pump;
  m.start();
  ASSERT_TRUE(run_until(
      m.backends, [&] { return m.pump_on(); }, 5s));
  ASSERT_TRUE(run_until(
      m.backends, [&] { return m.sprayer->pressure().sensor_ok; }, 5s));

  // The pressure loop is told to stop the pump and gets stuck doing it.
  pump.stall = true;
  m.params.pump_enabled = false;
  m.sprayer->set_params(m.params);
  ASSERT_TRUE(run_until(
      m.backends, [&] { return pump.stalled_once.load(); }, 1s));
  const std::uint64_t frozen = m.sprayer->pressure().cycles;
  EXPECT_TRUE(run_until(
      m.backends, [&] { return !m.pump_on(); }, 300ms))
      << "the pump kept running behind a stalled pressure loop: " << m.backends.describe_outputs();
  EXPECT_EQ(m.sprayer->pressure().cycles, frozen) << "the loop really was stalled";
  EXPECT_EQ(m.sprayer->pressure_loop_stalls(), 1U);
  pump.stall = false;
  m.sprayer->stop();
}

TEST(CrossWatch, AStalledValveThreadStopsThePumpAndOpensTheReturnValve) {
  SprayingMachine m;
  StallingBank valves(*m.backends.valves, "ws-valve-pwm");
  m.backends.valves = &valves;
  m.start();
  ASSERT_TRUE(run_until(
      m.backends, [&] { return m.pump_on() && m.sprayer->pressure().closure > 0.05; }, 5s));

  valves.stall = true;
  ASSERT_TRUE(run_until(
      m.backends, [&] { return valves.stalled_once.load(); }, 2s));
  EXPECT_TRUE(run_until(
      m.backends,
      [&] {
        const PressureStatus p = m.sprayer->pressure();
        return !m.pump_on() && !p.pump_on && p.closure == 0.0 && p.valve_thread_stalls == 1;
      },
      300ms))
      << m.backends.describe_outputs();
  valves.stall = false;
  EXPECT_TRUE(run_until(
      m.backends, [&] { return m.pump_on(); }, 2s))
      << "pumping resumes once the valve thread runs again";
  m.sprayer->stop();
}

}  // namespace
}  // namespace weedspray::daemon
