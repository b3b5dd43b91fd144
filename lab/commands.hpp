// Subcommand registration for weedspray-lab. Each room owns one registration function and
// the source file(s) behind it; main.cpp only calls them.
#pragma once

#include <CLI/CLI.hpp>

namespace weedspray::lab {

// vision-eval, segment, bench-vision (lab/vision_commands.cpp)
void add_vision_commands(CLI::App& app);
// experiment NAME (lab/experiment_commands.cpp)
void add_experiment_commands(CLI::App& app);
// bench-pwm (lab/io_commands.cpp)
void add_io_commands(CLI::App& app);
// soak (lab/soak_command.cpp)
void add_soak_command(CLI::App& app);

}  // namespace weedspray::lab
