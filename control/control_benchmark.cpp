// SPDX-License-Identifier: Apache-2.0
// weedspray-control-bench: per-call cost of the control algorithms on the real-time paths
// (Google Benchmark prints the figures). Run: build/<dir>/control/weedspray-control-bench
#include <benchmark/benchmark.h>

#include <chrono>
#include <vector>

#include "control/fuzzy_pid.hpp"
#include "control/nozzle_scheduler.hpp"
#include "control/odometry.hpp"
#include "control/pid.hpp"
#include "control/pwm_schedule.hpp"
#include "control/spray_rate_law.hpp"

namespace weedspray::control {
namespace {

FuzzyPidConfig pressure_loop() {
  FuzzyPidConfig config;
  config.base.gains = {0.8, 2.0, 0.01};
  config.correction_weights = {0.05, 0.1, 0.001};
  config.error_range = 0.4;
  return config;
}

void BM_PidUpdate(benchmark::State& state) {
  Pid pid(pressure_loop().base);
  double y = 0.0;
  for (auto _ : state) {
    const double u = pid.update(0.2, y, 0.01);
    y += (0.4 * u - y) * 0.05;
    benchmark::DoNotOptimize(y);
  }
}
BENCHMARK(BM_PidUpdate);

void BM_FuzzyPidUpdateWithTable(benchmark::State& state) {
  FuzzyPid pid(pressure_loop());
  double y = 0.0;
  for (auto _ : state) {
    const double u = pid.update(0.2, y, 0.01);
    y += (0.4 * u - y) * 0.05;
    if (y > 0.19) y = 0.0;  // keep the error moving over the table
    benchmark::DoNotOptimize(y);
  }
}
BENCHMARK(BM_FuzzyPidUpdateWithTable);

void BM_FuzzyInferExact(benchmark::State& state) {
  const FuzzyInferenceConfig config{state.range(0) == 0 ? FuzzyDefuzzification::kSampledCentroid
                                                        : FuzzyDefuzzification::kTermCentres,
                                    0.01};
  double qe = -6.0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(fuzzy_infer(qe, 1.3, config));
    qe = qe > 6.0 ? -6.0 : qe + 0.37;
  }
}
BENCHMARK(BM_FuzzyInferExact)->Arg(0)->Arg(1)->ArgName("term_centres");

void BM_FuzzyTableBuild(benchmark::State& state) {
  const FuzzyInferenceConfig config{};
  for (auto _ : state) {
    FuzzyGainTable table(config, static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(table.lookup(0.1, 0.2));
  }
}
BENCHMARK(BM_FuzzyTableBuild)->Arg(10)->Unit(benchmark::kMillisecond);

void BM_PwmNextEdge(benchmark::State& state) {
  PwmConfig config;
  config.valve_count = static_cast<std::size_t>(state.range(0));
  config.frequency_hz = 20.0;
  PwmSchedule pwm(config);
  for (std::size_t v = 0; v < config.valve_count; ++v) pwm.set_duty(v, 10.0 + 2.5 * v);
  pwm.start(std::chrono::nanoseconds(0));
  for (auto _ : state) benchmark::DoNotOptimize(pwm.next_edge());
}
BENCHMARK(BM_PwmNextEdge)->Arg(4)->Arg(32)->ArgName("valves");

void BM_SchedulerDutyAt(benchmark::State& state) {
  NozzleSchedulerConfig config;
  config.nozzles = 4;
  config.rows = 2;
  config.plan_capacity = static_cast<std::size_t>(state.range(0));
  NozzleScheduler scheduler(config);
  const std::vector<double> duties(8, 50.0);
  for (int f = 0; f < static_cast<int>(config.plan_capacity); ++f) {
    scheduler.add_frame(2.0 * f, duties);
  }
  double d = 0.0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(scheduler.duty_at(2, d, 1.0));
    d = d > 100.0 ? 0.0 : d + 0.01;
  }
}
BENCHMARK(BM_SchedulerDutyAt)->Arg(64)->ArgName("capacity");

void BM_OdometryUpdate(benchmark::State& state) {
  Odometry odometry(OdometryConfig{});
  std::uint64_t count = 0;
  std::chrono::nanoseconds now{0};
  for (auto _ : state) {
    now += std::chrono::milliseconds(1);
    ++count;
    odometry.update(count, now, now);
    benchmark::DoNotOptimize(odometry.distance_at(now - std::chrono::milliseconds(30)));
  }
}
BENCHMARK(BM_OdometryUpdate);

void BM_SprayDecision(benchmark::State& state) {
  const SprayLawConfig law{};
  const NozzleLine line{};
  double density = 0.0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(spray_decision(law, line, density, 1.1, 0.38));
    density = density > 1.0 ? 0.0 : density + 0.013;
  }
}
BENCHMARK(BM_SprayDecision);

}  // namespace
}  // namespace weedspray::control

BENCHMARK_MAIN();
