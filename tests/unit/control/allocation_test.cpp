// SPDX-License-Identifier: Apache-2.0
// The per-cycle functions of the control algorithms must not allocate: this executable
// replaces the global operator new and counts the calls made while they run.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <new>
#include <vector>

#include "control/flow_feedback.hpp"
#include "control/fuzzy_pid.hpp"
#include "control/nozzle_command_step.hpp"
#include "control/nozzle_scheduler.hpp"
#include "control/odometry.hpp"
#include "control/pressure_controller.hpp"
#include "control/pwm_schedule.hpp"
#include "control/spray_rate_law.hpp"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

// The replacement operator new below allocates with malloc, so free() IS the matching release;
// GCC cannot see that once it inlines both and warns.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}

namespace weedspray::control {
namespace {

using namespace std::chrono_literals;

TEST(Allocation, PerCycleFunctionsDoNotAllocate) {
  // Construction may allocate.
  FuzzyPidConfig loop;
  loop.base.gains = {0.8, 2.0, 0.01};
  loop.correction_weights = {0.05, 0.1, 0.001};
  PressureController fuzzy(PressureControlMode::kFuzzyPid, loop);
  PressureController plain(PressureControlMode::kPid, loop);
  PwmConfig pwm_config;
  pwm_config.valve_count = 8;
  PwmSchedule pwm(pwm_config);
  NozzleSchedulerConfig scheduler_config;
  scheduler_config.rows = 2;
  NozzleScheduler scheduler(scheduler_config);
  Odometry odometry(OdometryConfig{});
  FlowTrim trim(FlowTrimConfig{});
  FlowTrimWindows trim_windows(0.1);
  const std::vector<double> levels{0, 20, 40, 60, 80, 100};
  DutyQuantiser quantiser(levels, 2.0);
  const std::vector<double> frame(8, 40.0);
  const std::vector<double> duties{10, 20, 30, 40, 50, 60, 70, 80};
  NozzleCommandConfig command_config;
  command_config.nozzles = 8;
  command_config.quantiser_levels_pct = {0, 20, 40, 60, 80, 100};
  command_config.quantiser_level_count = 6;
  NozzleCommandStep command(command_config);
  const std::vector<double> target_flows{0.0, 0.3, 0.35, 0.4, 0.45, 0.5, 0.55, 0.6};
  const std::vector<NozzleLine> lines(8);

  const long before = g_allocations.load();
  double y = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const double u = fuzzy.update(0.2, y, 0.01) + plain.update(0.2, y, 0.01);
    y += (0.2 * u - y) * 0.05;
    pwm.set_duties(duties);
    pwm.next_edge();
    odometry.update(static_cast<std::uint64_t>(i), i * 1ms, i * 1ms);
    if (i % 100 == 0) scheduler.add_frame(odometry.distance_at(i * 1ms), frame);
    const double duty = scheduler.duty_at(i % 4, odometry.distance_m(), odometry.speed_m_per_s());
    const SprayDecision d = spray_decision(SprayLawConfig{}, NozzleLine{}, 0.6, 1.0, 0.4);
    FlowTrimInput window;
    const FlowTrimTick tick{promised_flow_l_per_min(NozzleLine{}, d.duty_pct, 0.4), 0.5, 0.01,
                            static_cast<std::uint64_t>(i) * 3};
    if (trim_windows.tick(0.01, tick, 8500.0, window)) trim.update(window);
    trimmed_duty_pct(NozzleLine{}, d.duty_pct, trim.correction(), 0.4);
    quantiser.quantise(duty + d.duty_pct * 0.01);
    NozzleCommandInputs in;
    in.dt_s = 0.002;
    in.spraying = i % 500 < 400;
    in.trim = true;
    in.pressure_mpa = 0.4 + y * 0.01;
    in.setpoint_mpa = 0.4;
    in.pulses = static_cast<std::uint64_t>(i) * 3;
    in.pulses_per_litre = 8500.0;
    in.target_flow_l_per_min = target_flows;
    in.lines = lines;
    command.step(in);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  // The counter really counts.
  auto* probe = new std::vector<int>(3);
  EXPECT_GT(g_allocations.load() - before, 0);
  delete probe;
}

}  // namespace
}  // namespace weedspray::control
