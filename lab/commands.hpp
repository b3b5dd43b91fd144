// SPDX-License-Identifier: Apache-2.0
// Subcommand registration for weedspray-lab. Each room owns one registration function and
// the source file(s) behind it; main.cpp only calls them.
#pragma once

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

namespace weedspray::lab {

// vision-eval, segment, bench-vision (lab/vision_commands.cpp)
void add_vision_commands(CLI::App& app);
// experiment NAME (lab/experiment_commands/: register.cpp, one file per NAME)
void add_experiment_commands(CLI::App& app);
// bench-pwm (lab/io_commands.cpp)
void add_io_commands(CLI::App& app);
// soak (lab/soak_command.cpp)
void add_soak_command(CLI::App& app);
// hil-frames (lab/hil_frames.cpp)
void add_hil_frames_command(CLI::App& app);

// CLI11 callbacks cannot return an exit code: errors become CLI::RuntimeError after a clear
// message naming the file or argument.
template <typename Function>
void run_reporting_errors(Function&& function) {
  int code = 0;
  try {
    code = function();
  } catch (const std::exception& error) {
    std::cerr << "weedspray-lab: " << error.what() << "\n";
    code = 1;
  }
  if (code != 0) throw CLI::RuntimeError(code);
}

}  // namespace weedspray::lab
