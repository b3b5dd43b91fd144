// SPDX-License-Identifier: Apache-2.0
// Command line of weedsprayd.
#pragma once

#include <string>
#include <vector>

namespace weedspray::daemon {

struct Options {
  std::string config_path;    // main configuration file
  bool config_given = false;  // --config was on the command line
  bool resume = false;        // sim: continue the last simulation's totals
  bool check_config = false;
  bool check_hardware = false;  // --hardware: with --check-config, what hardware mode needs
  bool dump_config = false;
  bool print_default_config = false;
  bool sim = false;              // simulated hydraulics, pulses and camera
  bool user_bus = false;         // session bus instead of the system bus
  bool no_bus = false;           // run without D-Bus (sim on a machine without a session bus)
  bool safe_outputs = false;     // write the outputs' safe values and exit (ExecStopPost)
  std::string output_manifest;   // hardware mode: the resolved configuration written here
  std::string sim_images;        // overrides sim.images_dir
  std::string state_dir;         // overrides daemon.state_dir
  std::string valve_state_file;  // sim: final valve states written here on exit
  std::string sim_truth_file;    // sim: the plant's true sprayed volume written here on exit
  double run_seconds = 0;        // stop by itself after this long (0 = until a signal)
  std::string timing_report;     // on exit: real-time loop lateness as JSON here ("-" = stdout)
  // Sim only: faults injected into the plant, "NAME@SECONDS" (see daemon/backends/sim_faults.hpp).
  std::vector<std::string> sim_faults;
};

}  // namespace weedspray::daemon
