// SPDX-License-Identifier: Apache-2.0
#include "daemon/backends/sim_faults.hpp"

#include <cerrno>
#include <cstdlib>
#include <string>
#include <string_view>
#include <utility>

#include "sim/plant/hydraulic_plant.hpp"

namespace weedspray::daemon {
namespace {

// The number N of a fault named PREFIX + N, N one or two digits in 1..max ("meter_drift_8"
// with prefix "meter_drift_" -> 8); else nullopt.
std::optional<int> number_after(std::string_view name, std::string_view prefix, int max) {
  if (!name.starts_with(prefix)) return std::nullopt;
  const std::string_view digits = name.substr(prefix.size());
  if (digits.empty() || digits.size() > 2 ||
      digits.find_first_not_of("0123456789") != std::string_view::npos)
    return std::nullopt;
  int n = 0;
  for (const char c : digits) n = n * 10 + (c - '0');
  if (n < 1 || n > max) return std::nullopt;
  return n;
}

// "_blocked_30" -> 0.30 (a nozzle 30 % blocked: the calibration and health tests' worn tip).
std::optional<double> partial_blockage(std::string_view suffix) {
  const auto percent = number_after(suffix, "_blocked_", 99);
  if (!percent) return std::nullopt;
  return *percent / 100.0;
}

}  // namespace

std::optional<SimFault> parse_sim_fault(const std::string& text) {
  const auto at = text.find('@');
  if (at == std::string::npos) return std::nullopt;
  SimFault fault;
  fault.name = text.substr(0, at);
  const std::string time = text.substr(at + 1);
  char* end = nullptr;
  fault.at_s = std::strtod(time.c_str(), &end);
  if (time.empty() || *end != '\0' || !(fault.at_s >= 0)) return std::nullopt;
  using Plant = sim::plant::HydraulicPlant;
  if (fault.name == "camera_gone" || fault.name == "camera_back" || fault.name == "tank_silent" ||
      fault.name == "tank_ok" || fault.name == "estop_open" || fault.name == "estop_closed") {
    fault.device = fault.name;
  } else if (fault.name == "sensor_ok") {
    fault.apply = [](Plant& p) {
      p.set_sensor_wire_broken(false);
      p.set_sensor_shorted(false);
    };
  } else if (fault.name == "filter_ok") {
    fault.apply = [](Plant& p) { p.set_filter_blockage(0.0); };
  } else if (fault.name == "tank_refill") {
    fault.apply = [](Plant& p) { p.set_tank_level_l(p.params().tank.capacity_l); };
  } else if (fault.name == "sensor_open") {
    fault.apply = [](Plant& p) { p.set_sensor_wire_broken(true); };
  } else if (fault.name == "sensor_short") {
    fault.apply = [](Plant& p) { p.set_sensor_shorted(true); };
  } else if (fault.name == "filter_blocked") {
    fault.apply = [](Plant& p) { p.set_filter_blockage(1.0); };
  } else if (fault.name == "tank_empty") {
    fault.apply = [](Plant& p) { p.set_tank_level_l(0.0); };
  } else if (const auto up = number_after(fault.name, "meter_drift_", 30),
             down = number_after(fault.name, "meter_drift_minus_", 30);
             up || down) {
    // The meter's true K moves (a worn turbine, deposits): it counts that much more (or fewer)
    // pulses per litre than its calibration says.
    const double drift = up ? *up / 100.0 : -*down / 100.0;
    fault.apply = [drift](Plant& p) { p.set_meter_drift(drift); };
  } else if (const auto worn = number_after(fault.name, "nozzles_worn_", 50)) {
    // Every tip worn alike: each sprays that much more at the same pressure and duty.
    const double wear = *worn / 100.0;
    fault.apply = [wear](Plant& p) {
      for (int i = 0; i < p.nozzle_count(); ++i) p.set_nozzle_wear(i, wear);
    };
  } else if (fault.name.starts_with("nozzle") && fault.name.size() >= 9 && fault.name[6] >= '0' &&
             fault.name[6] <= '7' &&
             (fault.name.substr(7) == "_blocked" || fault.name.substr(7) == "_ok" ||
              partial_blockage(fault.name.substr(7)))) {
    const int nozzle = fault.name[6] - '0';
    const double blockage = fault.name.ends_with("_ok") ? 0.0
                            : fault.name.ends_with("_blocked")
                                ? 1.0
                                : *partial_blockage(fault.name.substr(7));
    fault.apply = [nozzle, blockage](Plant& p) {
      if (nozzle < p.nozzle_count()) p.set_nozzle_blockage(nozzle, blockage);
    };
  } else if (fault.name.starts_with("valve") && fault.name.size() >= 7 && fault.name[5] >= '0' &&
             fault.name[5] <= '7' &&
             (fault.name.substr(6) == "_stuck_open" || fault.name.substr(6) == "_freed")) {
    const int valve = fault.name[5] - '0';
    const bool stuck = fault.name.ends_with("_stuck_open");
    fault.apply = [valve, stuck](Plant& p) {
      if (valve < p.nozzle_count()) p.set_valve_stuck_open(valve, stuck);
    };
  } else {
    constexpr std::pair<const char*, OutputRole> kOutputs[] = {
        {"valve", OutputRole::kValves},        {"pump", OutputRole::kPump},
        {"buzzer", OutputRole::kBuzzer},       {"led", OutputRole::kLed},
        {"heartbeat", OutputRole::kHeartbeat}, {"return_valve", OutputRole::kReturnValve}};
    for (const auto& [prefix, role] : kOutputs) {
      const std::string p(prefix);
      if (fault.name == p + "_write_fail" || fault.name == p + "_write_ok") {
        fault.output = role;
        fault.output_error = fault.name.ends_with("_fail") ? EIO : 0;
        return fault;
      }
    }
    // return_valve_write_fail_N: a Modbus module that misses N answers, then answers again.
    const std::string_view counted = "return_valve_write_fail_";
    if (fault.name.starts_with(counted)) {
      const auto writes = number_after(fault.name, counted, 99);
      if (!writes) return std::nullopt;
      fault.output = OutputRole::kReturnValve;
      fault.output_error = EIO;
      fault.output_write_count = *writes;
      return fault;
    }
    return std::nullopt;
  }
  return fault;
}

}  // namespace weedspray::daemon
