// SPDX-License-Identifier: Apache-2.0
// weedspray-lab: reproduce the papers' tables and figures on this machine.
#include <CLI/CLI.hpp>

#include "lab/commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"weedspray-lab: vision evaluation, benchmarks and sprayer experiments"};
  app.require_subcommand(1);
  weedspray::lab::add_vision_commands(app);
  weedspray::lab::add_experiment_commands(app);
  weedspray::lab::add_io_commands(app);
  weedspray::lab::add_soak_command(app);
  weedspray::lab::add_hil_frames_command(app);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
