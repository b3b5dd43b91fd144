// SPDX-License-Identifier: Apache-2.0
// weedsprayd: command line, then either a configuration check or the daemon itself.
#include <CLI/CLI.hpp>
#include <iostream>

#include "daemon/backends/sim_faults.hpp"
#include "daemon/config/config.hpp"
#include "daemon/config/config_schema.hpp"
#include "daemon/config/hardware_check.hpp"
#include "daemon/config/model_timing.hpp"
#include "daemon/config/options.hpp"
#include "daemon/config/vision_config.hpp"
#include "daemon/run.hpp"
#include "daemon/supervision/alarm_catalog.hpp"

int main(int argc, char** argv) {
  using namespace weedspray::daemon;
  Options options;
  options.config_path = kDefaultConfigPath;
  CLI::App app{"weedsprayd: camera-guided variable-rate weed sprayer controller"};
  auto* config_option = app.add_option("--config", options.config_path,
                                       "main configuration file (drop-ins: conf.d/)");
  app.add_flag("--resume", options.resume,
               "sim: continue the last simulation's totals (otherwise they start from zero)");
  app.add_flag("--check-config", options.check_config, "validate the configuration and exit");
  app.add_flag("--hardware", options.check_hardware,
               "with --check-config: also check what hardware mode needs (valve lines, the "
               "heartbeat, the wheel line) and that every device named exists; every problem "
               "is listed");
  app.add_flag("--dump-config", options.dump_config, "print the effective configuration");
  app.add_flag("--print-default-config", options.print_default_config,
               "print every key, documented, at its default");
  std::string alarm_catalog_format;
  app.add_option("--print-alarm-catalog", alarm_catalog_format,
                 "print what every alarm means and what to do, as the journal's message catalog "
                 "(journal) or as a Markdown table (markdown)")
      ->check(CLI::IsMember({"journal", "markdown"}));
  app.add_flag("--sim", options.sim, "simulated hydraulics, pulses and camera");
  app.add_flag("--user", options.user_bus, "use the session bus instead of the system bus");
  app.add_flag("--no-bus", options.no_bus, "run without D-Bus");
  app.add_flag("--safe-outputs", options.safe_outputs,
               "write every configured output's safe value and exit (the unit's ExecStopPost: "
               "covers kill -9 and crashes)");
  app.add_option("--output-manifest", options.output_manifest,
                 "hardware mode: write the resolved configuration here at start (the unit: "
                 "/run/weedspray/outputs.toml); the exit watcher and --safe-outputs read it, not "
                 "the editable files");
  app.add_option("--sim-images", options.sim_images,
                 "field image folder (PNG or JPEG files) for --sim");
  app.add_option("--state-dir", options.state_dir, "overrides daemon.state_dir");
  app.add_option("--valve-state-file", options.valve_state_file,
                 "sim: write the final valve states here on exit");
  app.add_option("--sim-truth-file", options.sim_truth_file,
                 "sim: write the plant's true sprayed volume here on exit (the soak's reference)");
  app.add_option("--run-seconds", options.run_seconds, "exit by itself after this long")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--timing-report", options.timing_report,
                 "on exit, write each real-time loop's lateness (p50/p99/max, misses) as JSON "
                 "to this file (- = standard output)");
  app.add_option(
         "--sim-fault", options.sim_faults,
         std::string("sim: inject NAME@SECONDS (") + weedspray::daemon::kSimFaultNames + ")")
      ->check([](const std::string& value) {
        return weedspray::daemon::parse_sim_fault(value) ? std::string()
                                                         : "expected NAME@SECONDS, got " + value;
      });
  CLI11_PARSE(app, argc, argv);
  options.config_given = config_option->count() > 0;
  if (!options.sim_faults.empty() && !options.sim) {
    std::cerr << "weedsprayd: --sim-fault needs --sim\n";
    return 1;
  }

  if (options.safe_outputs) return write_safe_outputs(options);
  if (options.print_default_config) {
    std::cout << documented_config();
    return 0;
  }
  if (!alarm_catalog_format.empty()) {
    std::cout << (alarm_catalog_format == "journal" ? weedspray::daemon::journal_catalog()
                                                    : weedspray::daemon::alarm_catalog_markdown());
    return 0;
  }
  if (options.check_hardware && !options.check_config) {
    std::cerr << "weedsprayd: --hardware needs --check-config\n";
    return 1;
  }
  if (options.check_config || options.dump_config) {
    try {
      const Config config = load_config(options.config_path);
      if (options.dump_config) {
        std::cout << dump_config(config);
        return 0;
      }
      if (options.check_hardware) {
        const std::vector<ConfigError> problems = check_hardware(config);
        for (const auto& problem : problems) std::cerr << "weedsprayd: " << problem.what() << "\n";
        if (!problems.empty()) {
          std::cerr << "weedsprayd: " << problems.size()
                    << " problem(s) keep hardware mode from starting\n";
          return 1;
        }
      }
      if (!options.sim && require_heartbeat(config))
        std::cerr << "weedsprayd: warning: " << kNoHeartbeatWarning << "\n";
      if (!options.sim && require_estop(config))
        std::cerr << "weedsprayd: warning: " << kNoEstopWarning << "\n";
      std::cout << "configuration OK" << (options.check_hardware ? " for hardware mode" : "")
                << ":";
      for (const auto& file : config.files) std::cout << " " << file;
      std::cout << "\n";
      for (const auto& line : describe_model_use(config)) std::cout << line << "\n";
      for (const auto& line : time_model_use(config)) std::cout << line << "\n";
      return 0;
    } catch (const VisionKeyError& error) {
      std::cerr << "weedsprayd: " << error.key() << ": " << error.what() << "\n";
      return 1;
    } catch (const ConfigError& error) {
      std::cerr << "weedsprayd: " << error.what() << "\n";
      return 1;
    }
  }
  return run_daemon(options);
}
