// SPDX-License-Identifier: Apache-2.0
#include "daemon/backends/sim_driver.hpp"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

namespace weedspray::daemon {
namespace {

void print_status_line(const Status& s) {
  std::printf("%-8s P %.3f/%.3f MPa  Q %.3f L/min  v %.2f m/s  d %.1f m  duty", s.state.c_str(),
              s.pressure_mpa, s.pressure_setpoint_mpa, s.flow_l_per_min, s.speed_m_per_s,
              s.distance_m);
  for (double duty : s.nozzle_duty_pct) std::printf(" %3.0f", duty);
  std::printf("  %.1f L %.0f m2 saved %.0f%%  lat %.2f ms (p99 %.2f)", s.volume_sprayed_l,
              s.area_covered_m2, s.savings_pct, s.vision_latency_ms, s.vision_latency_p99_ms);
  if (!s.alarms.empty()) {
    std::printf("  ALARMS:");
    for (const auto& alarm : s.alarms) std::printf(" %s", alarm.c_str());
  }
  std::printf("\n");
  std::fflush(stdout);
}

}  // namespace

SimDriver::SimDriver(Backends& backends, const Options& options)
    : backends_(backends), options_(options) {}

std::function<double()> SimDriver::delivered_litres() const {
  if (!backends_.plant_truth) return {};
  return [truth = backends_.plant_truth] {
    return std::strtod(truth().c_str() + std::strlen("sprayed_l="), nullptr);
  };
}

bool SimDriver::runs_without_bus(const char* why) {
  // Nothing could send Start: the caller sprays as soon as the simulation is up.
  spdlog::warn("{}; simulating without D-Bus, spraying at once", why);
  return true;
}

void SimDriver::start() {
  if (backends_.drive_world) backends_.drive_world(0.0);
}

void SimDriver::step(double t_s) {
  if (backends_.drive_world) backends_.drive_world(t_s);
  if (!backends_.with_plant) return;
  faults_done_.resize(options_.sim_faults.size(), false);
  for (std::size_t i = 0; i < options_.sim_faults.size(); ++i) {
    const auto fault = parse_sim_fault(options_.sim_faults[i]);
    if (faults_done_[i] || !fault || t_s < fault->at_s) continue;
    apply(*fault);
    faults_done_[i] = true;
  }
}

CommandResult SimDriver::inject_fault(const std::string& name) {
  if (!backends_.with_plant) return WorldDriver::inject_fault(name);
  const auto fault = parse_sim_fault(name + "@0");
  if (!fault)
    return {kErrorInvalidArgument,
            "InjectSimFault: unknown fault '" + name + "' (known: " + kSimFaultNames + ")"};
  apply(*fault);
  return {};
}

void SimDriver::apply(const SimFault& fault) {
  spdlog::warn("sim: injecting fault {}", fault.name);
  if (fault.output) {
    if (backends_.fail_output_writes)
      backends_.fail_output_writes(*fault.output, fault.output_error, fault.output_write_count);
  } else if (!fault.device.empty()) {
    if (backends_.device_fault) backends_.device_fault(fault.device);
  } else {
    backends_.with_plant(fault.apply);
  }
}

void SimDriver::status_published(const Status& status, double t_s) {
  if (t_s - last_print_s_ < 1.0) return;
  last_print_s_ = t_s;
  print_status_line(status);
}

void SimDriver::finish() {
  if (!options_.valve_state_file.empty() && backends_.describe_outputs) {
    std::ofstream(options_.valve_state_file) << backends_.describe_outputs();
  }
  if (!options_.sim_truth_file.empty() && backends_.plant_truth) {
    std::ofstream(options_.sim_truth_file) << backends_.plant_truth();
  }
}

}  // namespace weedspray::daemon
