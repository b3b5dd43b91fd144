// SPDX-License-Identifier: Apache-2.0
// bench-pwm: edge timing of the real valve PWM thread on this machine.
#pragma once

#include <vector>

namespace weedspray::lab {

struct BenchPwmOptions {
  double seconds = 10.0;
  double frequency_hz = 5.0;
  std::vector<double> duty_pct{25.0, 50.0, 75.0, 40.0};
  int load_threads = 2;
  bool json = false;
  bool normal_priority = false;  // for comparison: the PWM thread without SCHED_FIFO
};

// Prints the figures; returns 0, or non-zero with a message on stderr.
int run_bench_pwm(const BenchPwmOptions& options);

}  // namespace weedspray::lab
