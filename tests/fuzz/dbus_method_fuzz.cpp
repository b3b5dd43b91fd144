// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: arbitrary D-Bus method calls on the daemon's dispatch
// (handle_method_call): any member name, argument signature and values, with a handler that
// does what the daemon's does with the strings it gets (parse_sim_fault on InjectSimFault's
// name). A call must come back as a reply or an error, never a crash or an escaped exception.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "daemon/backends/sim_faults.hpp"
#include "daemon/bus/dbus_service.hpp"
#include "tests/fuzz/offline_bus.hpp"

namespace {

using weedspray::daemon::CommandResult;
using weedspray::daemon::ReloadReply;

class Handler final : public weedspray::daemon::CommandHandler {
 public:
  CommandResult start() override { return {}; }
  CommandResult stop() override { return {}; }
  CommandResult set_pressure_setpoint(double mpa) override {
    if (!(mpa >= 0.05 && mpa < 1.0))
      return {weedspray::daemon::kErrorInvalidArgument, "out of range"};
    return {};
  }
  CommandResult set_decision_threshold(double threshold) override {
    if (!(threshold >= 0.0 && threshold <= 1.0))
      return {weedspray::daemon::kErrorInvalidArgument, "out of range"};
    return {};
  }
  CommandResult set_target_rate(double l_per_ha) override {
    if (!(l_per_ha > 0.0 && l_per_ha <= 5000.0))
      return {weedspray::daemon::kErrorInvalidArgument, "out of range"};
    return {};
  }
  CommandResult reload_config(ReloadReply reply) override {
    reply({});
    return {};
  }
  CommandResult clear_alarms() override { return {}; }
  CommandResult inject_sim_fault(const std::string& name) override {
    if (!weedspray::daemon::parse_sim_fault(name + "@0"))
      return {weedspray::daemon::kErrorInvalidArgument, "unknown fault"};
    return {};
  }
  CommandResult calibrate_wheel(double run_distance_m, std::uint64_t& request) override {
    if (!(run_distance_m >= 10.0 && run_distance_m <= 5000.0))
      return {weedspray::daemon::kErrorInvalidArgument, "out of range"};
    request = 1;
    return {};
  }
  CommandResult start_catch_test(double seconds) override {
    if (!(seconds >= 1.0 && seconds <= 600.0))
      return {weedspray::daemon::kErrorInvalidArgument, "out of range"};
    return {};
  }
  CommandResult calibrate_meter(double volume_l) override {
    if (!(volume_l > 0.0 && volume_l < 1000.0))
      return {weedspray::daemon::kErrorInvalidArgument, "out of range"};
    return {};
  }
  CommandResult calibrate_nozzles() override { return {}; }
  CommandResult test_valve(std::uint32_t nozzle, double duty_pct, double seconds) override {
    if (nozzle >= 4 || !(duty_pct > 0 && duty_pct <= 100) || !(seconds >= 1 && seconds <= 60))
      return {weedspray::daemon::kErrorInvalidArgument, "out of range"};
    return {};
  }
  CommandResult test_pump(double seconds) override {
    if (!(seconds >= 1 && seconds <= 120))
      return {weedspray::daemon::kErrorInvalidArgument, "out of range"};
    return {};
  }
  CommandResult motion(double& speed_m_per_s, double& distance_m, std::uint64_t& time_ns,
                       weedspray::daemon::SharedFix&) override {
    speed_m_per_s = 1;
    distance_m = 2;
    time_ns = 3;
    return {};
  }
  CommandResult feed_shared_motion(double speed_m_per_s, double, std::uint64_t,
                                   const weedspray::daemon::SharedFix&) override {
    if (!(speed_m_per_s >= 0 && speed_m_per_s <= 50))
      return {weedspray::daemon::kErrorInvalidArgument, "out of range"};
    return {};
  }
  void bus_lost() override {}
  // One camera; its reply at once (the daemon's comes from a later main-loop tick).
  CommandResult snapshot(std::uint32_t camera, weedspray::daemon::SnapshotReply reply) override {
    if (camera != 0) return {weedspray::daemon::kErrorInvalidArgument, "no such camera"};
    static constexpr std::uint8_t kPng[] = {0x89, 'P', 'N', 'G'};
    reply({}, kPng);
    return {};
  }
};

constexpr const char* kMembers[] = {"Start",
                                    "Stop",
                                    "SetPressureSetpoint",
                                    "ReloadConfig",
                                    "ClearAlarms",
                                    "InjectSimFault",
                                    "Get",
                                    "SetPressure",
                                    "Snapshot",
                                    "CalibrateWheel",
                                    "StartCatchTest",
                                    "CalibrateMeter",
                                    "CalibrateNozzles"};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static weedspray::testing::OfflineBus bus;
  static Handler handler;
  if (size < 2) return 0;
  const char* member = kMembers[data[0] % (sizeof kMembers / sizeof *kMembers)];
  const std::uint8_t shape = data[1];
  data += 2;
  size -= 2;
  sd_bus_message* m = bus.call(member);
  // Arguments of any of the kinds a client could send, built from the rest of the input.
  double number = 0;
  std::int32_t integer = 0;
  if (size >= sizeof number) std::memcpy(&number, data, sizeof number);
  if (size >= sizeof integer) std::memcpy(&integer, data, sizeof integer);
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::string utf8_safe = text.substr(0, text.find('\0'));
  switch (shape % 7) {
    case 0:
      break;
    case 1:
      sd_bus_message_append(m, "d", number);
      break;
    case 2:
      sd_bus_message_append(m, "s", utf8_safe.c_str());
      break;  // sd-bus refuses bad UTF-8
    case 3:
      sd_bus_message_append(m, "i", integer);
      break;
    case 4:
      sd_bus_message_append(m, "ds", number, utf8_safe.c_str());
      break;
    case 5:
      sd_bus_message_append(m, "as", 2, utf8_safe.c_str(), "x");
      break;
    case 6:
      sd_bus_message_append(m, "u", static_cast<std::uint32_t>(integer));
      break;
  }
  if (weedspray::testing::OfflineBus::seal(m) >= 0) {
    sd_bus_error error = SD_BUS_ERROR_NULL;
    handle_method_call(m, handler, &error);
    sd_bus_error_free(&error);
  }
  sd_bus_message_unref(m);
  return 0;
}
