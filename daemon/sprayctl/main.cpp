// SPDX-License-Identifier: Apache-2.0
// sprayctl: a small command-line client of weedsprayd over D-Bus (sd-bus).
//   sprayctl [--user] [--json] status|monitor|top|start|stop|set-pressure MPA|set-threshold
//   VALUE|set-rate L_PER_HA|alarms|clear-alarms|reload|snapshot [--camera N]
//   OUT.png|calibrate-wheel [--distance M] sprayctl calibrate meter --seconds S | --volume L catch
//   test, then the collected volume sprayctl calibrate nozzles                            each
//   nozzle's line over a duty sweep sprayctl test valve N [--duty P] [--seconds S] | test pump
//   [--seconds S] | inputs
//                                                         commissioning
//   sprayctl export-map ...   runs weedspray-export-map (no bus; GDAL stays out of sprayctl)
// Exit status: 0 done, 1 refused by the daemon or failed, 2 usage, 3 weedsprayd not reachable
// (docs/man/sprayctl.1.in).
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "daemon/sprayctl/bus_client.hpp"
#include "daemon/sprayctl/value_text.hpp"
#include "daemon/sprayctl/views.hpp"

using namespace weedspray::sprayctl;

namespace {

// Replaces this process with weedspray-export-map: the one beside sprayctl (an install's bin
// folder, or the build tree's daemon/), else the first on PATH. Returns only on failure.
int exec_export_map(const std::vector<std::string>& args) {
  std::vector<std::string> argv_strings{"weedspray-export-map"};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv_c;
  for (auto& a : argv_strings) argv_c.push_back(a.data());
  argv_c.push_back(nullptr);
  char self[4096];
  const ssize_t n = ::readlink("/proc/self/exe", self, sizeof self - 1);
  if (n > 0) {
    std::string beside(self, static_cast<std::size_t>(n));
    beside = beside.substr(0, beside.rfind('/') + 1) + "weedspray-export-map";
    if (::access(beside.c_str(), X_OK) == 0) ::execv(beside.c_str(), argv_c.data());
  }
  ::execvp("weedspray-export-map", argv_c.data());
  std::cerr << "sprayctl: cannot run weedspray-export-map: " << std::strerror(errno)
            << " (it comes in the package weedspray-maps: apt install weedspray-maps; the arm64 "
               "build has no GDAL: export on a PC from a copy of the as-applied log folder)\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sprayctl: status and control of weedsprayd over D-Bus"};
  bool user_bus = false;
  bool json = false;
  double pressure_mpa = 0;
  app.add_flag("--user", user_bus, "use the session bus (weedsprayd --user)");
  app.add_flag("--json", json, "machine-readable output (one JSON object per line)");
  app.set_version_flag("--version", std::string("sprayctl ") + WEEDSPRAY_VERSION);
  app.require_subcommand(1);
  auto* status = app.add_subcommand("status", "show the sprayer's state and measurements");
  auto* monitor = app.add_subcommand(
      "monitor", "print property changes and alarms, each with its time, until Ctrl-C");
  auto* top = app.add_subcommand(
      "top",
      "a live view: state, pressure, flow, speed, L/ha, tank, vision, each nozzle's duty and "
      "health, alarms with what to do; redrawn until Ctrl-C");
  double top_interval_s = 1.0;
  int top_frames = 0;
  top->add_option("--interval", top_interval_s, "seconds between frames (0.1..60)")
      ->check(CLI::Range(0.1, 60.0))
      ->capture_default_str();
  top->add_option("--frames", top_frames, "stop after this many frames (0: until Ctrl-C)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  auto* start = app.add_subcommand("start", "start spraying");
  auto* stop = app.add_subcommand("stop", "stop spraying (valves closed, pump held)");
  auto* set_pressure = app.add_subcommand("set-pressure", "change the pressure set-point");
  set_pressure->add_option("MPA", pressure_mpa, "set-point in MPa")->required();
  auto* set_threshold = app.add_subcommand(
      "set-threshold",
      "change the decision threshold: the zone density below which nothing is sprayed "
      "(until the configuration is reloaded)");
  double threshold = 0;
  set_threshold->add_option("VALUE", threshold, "threshold, 0..1")->required();
  auto* set_rate = app.add_subcommand(
      "set-rate",
      "change the dose at full weed cover, in L/ha (until the configuration is reloaded)");
  double rate_l_per_ha = 0;
  set_rate->add_option("L_PER_HA", rate_l_per_ha, "dose in L/ha")->required();
  auto* alarms = app.add_subcommand("alarms", "list latched alarms");
  auto* clear_alarms = app.add_subcommand("clear-alarms", "clear latched alarms (leaves Fault)");
  auto* reload = app.add_subcommand("reload", "re-read the configuration");
  auto* snapshot = app.add_subcommand(
      "snapshot",
      "save a camera's latest frame with the weed/crop overlay, zone grid, densities "
      "and duties as a PNG (at most 2 a second)");
  std::uint32_t camera = 0;
  std::string snapshot_path;
  snapshot->add_option("--camera", camera, "camera index (0 = the first [[camera]])");
  snapshot->add_option("OUT", snapshot_path, "PNG file to write")->required();
  auto* calibrate_wheel = app.add_subcommand(
      "calibrate-wheel",
      "measure the wheel sensor's pulses per metre with the GNSS receiver: drive straight at a "
      "steady working speed; a turn or a stop starts the run again. Prints the value for "
      "wheel.pulses_per_metre");
  double run_distance_m = 100.0;
  double calibration_timeout_s = 600.0;
  calibrate_wheel->add_option("--distance", run_distance_m, "straight run, metres (10..5000)")
      ->capture_default_str();
  calibrate_wheel->add_option("--timeout", calibration_timeout_s, "give up after, seconds")
      ->capture_default_str();
  auto* calibrate = app.add_subcommand(
      "calibrate", "calibrate the flow meter or the nozzles (in Idle: pump on, not spraying)");
  calibrate->require_subcommand(1);
  auto* calibrate_meter = calibrate->add_subcommand(
      "meter",
      "catch test: --seconds S opens every valve for S s at the set-point (collect all the "
      "liquid); then --volume L enters the litres collected. The meter's pulses per litre is "
      "stored in the state directory and used instead of flow.pulses_per_litre");
  double catch_test_s = 0;
  double collected_l = 0;
  auto* seconds_option =
      calibrate_meter->add_option("--seconds", catch_test_s, "catch test length, s (1..600)");
  calibrate_meter->add_option("--volume", collected_l, "litres collected in the catch test")
      ->excludes(seconds_option);
  auto* calibrate_nozzles = calibrate->add_subcommand(
      "nozzles",
      "each nozzle alone over calibration.duties_pct at the set-point and PWM frequency, its "
      "flow from the line meter: each nozzle's line q = A s + b, stored in the state directory "
      "and used by the rate law (the [spray] line stays for a fit below "
      "calibration.min_r_squared)");
  double nozzle_timeout_s = 600.0;
  calibrate_nozzles->add_option("--timeout", nozzle_timeout_s, "give up after, seconds")
      ->capture_default_str();
  auto* test = app.add_subcommand(
      "test", "commissioning: one valve, or the pump alone (in Idle, run as a calibration)");
  test->require_subcommand(1);
  auto* test_valve = test->add_subcommand(
      "valve",
      "hold nozzle N's valve at --duty for --seconds with the pump on, the others closed; "
      "prints the meter's pulses and flow over it");
  std::uint32_t tested_nozzle = 0;
  double tested_duty_pct = 100.0;
  double valve_test_s = 5.0;
  test_valve->add_option("N", tested_nozzle, "nozzle index (0 = the first)")->required();
  test_valve->add_option("--duty", tested_duty_pct, "duty, % (> 0..100; 100 holds it open)")
      ->capture_default_str();
  test_valve->add_option("--seconds", valve_test_s, "how long, s (1..60)")->capture_default_str();
  auto* test_pump = test->add_subcommand(
      "pump",
      "run the pump holding the pressure set-point for --seconds with every valve closed; "
      "prints when the set-point was reached and the highest pressure");
  double pump_test_s = 20.0;
  test_pump->add_option("--seconds", pump_test_s, "how long, s (1..120)")->capture_default_str();
  auto* inputs = app.add_subcommand(
      "inputs",
      "each wired input as the hardware gives it: the pressure sensor's mA, pulse counts, "
      "the tank's reading, E-stop and key contacts (commissioning)");
  auto* export_map = app.add_subcommand(
      "export-map",
      "the as-applied log as a map a GIS opens: export-map [--from T] [--to T] --format "
      "geojson|gpkg|shp [--dir LOGDIR]... [--config FILE] OUT (runs weedspray-export-map; "
      "`sprayctl export-map --help` lists its options)");
  // Every argument after export-map, --help included, is the exporter's.
  export_map->prefix_command();
  export_map->set_help_flag();
  for (auto* sub : {status, monitor, alarms, inputs}) sub->add_flag("--json", json, "JSON output");
  // A bare `sprayctl` prints its usage; usage errors exit with their own status (CLI11's
  // default, 106 and up, says nothing to a script).
  app.name("sprayctl");
  if (argc == 1) {
    std::cerr << app.help();
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int status = app.exit(error);
    return status == 0 ? 0 : kExitUsage;
  }
  if (*export_map) return exec_export_map(export_map->remaining());
  if (*calibrate_meter && !(catch_test_s > 0) && !(collected_l > 0)) {
    std::cerr << "sprayctl: calibrate meter: --seconds S (start the catch test) or --volume L\n";
    return kExitUsage;
  }

  try {
    BusClient client(user_bus);
    if (*status) {
      print_status(std::cout, client.get_all(), json, std::chrono::system_clock::now());
    } else if (*monitor) {
      return client.follow_signals(
          [&](const std::string& kind, const std::string& name, const Value& value) {
            print_event(std::cout, kind, name, value, json, std::chrono::system_clock::now());
          });
    } else if (*top) {
      return run_top(client, top_interval_s, top_frames);
    } else if (*start) {
      client.call("Start");
    } else if (*stop) {
      client.call("Stop");
    } else if (*set_pressure) {
      client.call("SetPressureSetpoint", "d", pressure_mpa);
    } else if (*set_threshold) {
      client.call("SetDecisionThreshold", "d", threshold);
    } else if (*set_rate) {
      client.call("SetTargetRate", "d", rate_l_per_ha);
    } else if (*alarms) {
      const Value alarms_value = client.get("Alarms");
      std::cout << (json ? Value{{"Alarms", alarms_value},
                                 {"timestamp", utc_timestamp(std::chrono::system_clock::now())}}
                               .dump()
                         : text_value("Alarms", alarms_value))
                << "\n";
    } else if (*clear_alarms) {
      client.call("ClearAlarms");
    } else if (*reload) {
      client.call("ReloadConfig");
    } else if (*calibrate_meter) {
      return run_meter_calibration(client, catch_test_s, collected_l);
    } else if (*calibrate_nozzles) {
      return run_nozzle_calibration(client, nozzle_timeout_s);
    } else if (*test_valve) {
      return run_valve_test(client, tested_nozzle, tested_duty_pct, valve_test_s);
    } else if (*test_pump) {
      return run_pump_test(client, pump_test_s);
    } else if (*inputs) {
      print_inputs(std::cout, client.get("RawInputs"), json, std::chrono::system_clock::now());
    } else if (*calibrate_wheel) {
      return run_wheel_calibration(client, run_distance_m, calibration_timeout_s);
    } else if (*snapshot) {
      // Written here, by the operator's own process: the daemon runs as user weedspray and
      // never writes where a caller asks.
      const std::vector<std::uint8_t> png = client.snapshot(camera);
      std::ofstream out(snapshot_path, std::ios::binary | std::ios::trunc);
      out.write(reinterpret_cast<const char*>(png.data()),
                static_cast<std::streamsize>(png.size()));
      out.close();
      if (!out) throw BusError{"cannot write " + snapshot_path + ": " + std::strerror(errno)};
      std::cout << snapshot_path << ": " << png.size() << " bytes (camera " << camera << ")\n";
    }
  } catch (const BusError& error) {
    std::cerr << "sprayctl: " << error.message << "\n";
    return error.exit_status;
  }
  return 0;
}
