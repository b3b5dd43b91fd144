// SPDX-License-Identifier: Apache-2.0
// weedspray-lab io subcommands: bench-pwm.
#include <CLI/CLI.hpp>

#include "lab/commands.hpp"
#include "lab/io_bench_pwm.hpp"

namespace weedspray::lab {

void add_io_commands(CLI::App& app) {
  auto options = std::make_shared<BenchPwmOptions>();
  CLI::App* bench = app.add_subcommand(
      "bench-pwm",
      "Run the real valve PWM thread (SCHED_FIFO when permitted) on a timestamping sink under a "
      "CPU load it starts itself, and report edge timing error vs the schedule");
  bench->add_option("--seconds", options->seconds, "Duration of the run")
      ->check(CLI::Range(1.0, 3600.0));
  bench->add_option("--frequency", options->frequency_hz, "PWM frequency [Hz]")
      ->check(CLI::Range(1.0, 20.0));
  bench->add_option("--duty", options->duty_pct, "Duty per valve [%] (one value per valve)")
      ->check(CLI::Range(0.0, 100.0));
  bench
      ->add_option("--load-threads", options->load_threads,
                   "Busy threads loading the CPUs during the run (0 = none)")
      ->check(CLI::Range(0, 64));
  bench->add_flag("--normal-priority", options->normal_priority,
                  "Run the PWM thread at normal priority (for comparison with SCHED_FIFO)");
  bench->add_flag("--json", options->json, "Print one JSON object instead of text");
  bench->callback([options] {
    const int rc = run_bench_pwm(*options);
    if (rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace weedspray::lab
