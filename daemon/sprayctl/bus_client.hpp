// SPDX-License-Identifier: Apache-2.0
// sprayctl's connection to weedsprayd: property reads, method calls and the signal stream,
// with each failure turned into a BusError that says whether the daemon refused or is not
// there.
#pragma once

#include <systemd/sd-bus.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "daemon/sprayctl/bus_values.hpp"

namespace weedspray::sprayctl {

class BusClient {
 public:
  explicit BusClient(bool user_bus);
  ~BusClient();
  BusClient(const BusClient&) = delete;
  BusClient& operator=(const BusClient&) = delete;

  Properties get_all();
  Value get(const char* property);

  // Calls `method` without arguments or with one of `signature` ("d" or "u").
  void call(const char* method, const char* signature = "", double argument = 0);

  // TestValve(u nozzle, d duty %, d seconds).
  void test_valve(std::uint32_t nozzle, double duty_pct, double seconds);

  // Starts a wheel calibration; its request number.
  std::uint64_t calibrate_wheel(double run_distance_m);

  // Camera `camera`'s next frame with its overlay, as PNG bytes.
  std::vector<std::uint8_t> snapshot(std::uint32_t camera);

  // A property change or an alarm signal: kind "property", "alarm-raised" or "alarm-cleared".
  using EventHandler =
      std::function<void(const std::string& kind, const std::string& name, const Value& value)>;

  // Calls `handler` for each signal until SIGINT or SIGTERM; the exit status.
  int follow_signals(const EventHandler& handler);

 private:
  [[noreturn]] void fail(sd_bus_error& error, int r) const;
  BusError unreachable_bus(int r) const;
  static int on_signal(sd_bus_message* m, void* userdata, sd_bus_error*);

  std::string bus_kind_;
  sd_bus* bus_ = nullptr;
  const EventHandler* handler_ = nullptr;
};

}  // namespace weedspray::sprayctl
