// SPDX-License-Identifier: Apache-2.0
// The calibrations and commissioning tests sprayctl starts and follows until they end,
// printing each step.
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <thread>

#include "daemon/sprayctl/value_text.hpp"
#include "daemon/sprayctl/views.hpp"

namespace weedspray::sprayctl {

namespace {

// Follows the Calibration property until the run stops (done, cancelled or awaiting the
// catch test's volume), printing each new step; true when it ended as `wanted`.
bool follow_calibration(BusClient& client, const char* wanted, double timeout_s) {
  std::string last_message;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    const Value c = client.get("Calibration");
    const std::string message = c.value("message", "");
    const std::string state = c.value("state", "");
    if (message != last_message) {
      std::cout << "  [" << std::setw(3) << static_cast<int>(c.value("progress", 0.0) * 100)
                << " %] " << message << "\n"
                << std::flush;
      last_message = message;
    }
    if (state == "done" || state == "cancelled" || state == "awaiting_volume")
      return state == wanted;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  std::cerr << "sprayctl: not finished within " << timeout_s << " s\n";
  return false;
}

}  // namespace

int run_wheel_calibration(BusClient& client, double run_distance_m, double timeout_s) {
  const std::uint64_t request = client.calibrate_wheel(run_distance_m);
  std::cout << "wheel calibration " << request << ": drive straight for " << run_distance_m
            << " m at working speed\n"
            << std::flush;
  std::string last_state;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    const Value c = client.get("WheelCalibration");
    if (c.value("request", std::uint64_t{0}) == request) {
      const std::string state = c.value("state", "");
      if (state != last_state) {
        std::cout << "  " << state << (state == "waiting" ? " (for a straight run at speed)" : "")
                  << "\n"
                  << std::flush;
        last_state = state;
      }
      if (state == "done") {
        std::cout << std::fixed << std::setprecision(3) << c.value("pulses", std::uint64_t{0})
                  << " pulses over " << c.value("distance_m", 0.0) << " m\n"
                  << "[wheel]\npulses_per_metre = " << c.value("pulses_per_metre", 0.0) << "\n";
        return 0;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  std::cerr << "sprayctl: calibrate-wheel: no straight run of " << run_distance_m << " m within "
            << timeout_s << " s (state " << (last_state.empty() ? "not started" : last_state)
            << ")\n";
  return kExitRefused;
}

int run_meter_calibration(BusClient& client, double catch_test_s, double volume_l) {
  if (volume_l > 0) {
    client.call("CalibrateMeter", "d", volume_l);
    std::cout << "flow meter: " << text_value("MeterCalibration", client.get("MeterCalibration"))
              << "\n";
    return 0;
  }
  client.call("StartCatchTest", "d", catch_test_s);
  std::cout << "catch test: every valve open for " << catch_test_s
            << " s; collect the liquid of every nozzle\n"
            << std::flush;
  if (!follow_calibration(client, "awaiting_volume", catch_test_s + 30.0)) return kExitRefused;
  std::cout << "measure the collected litres, then: sprayctl calibrate meter --volume L\n";
  return 0;
}

int run_nozzle_calibration(BusClient& client, double timeout_s) {
  client.call("CalibrateNozzles");
  if (!follow_calibration(client, "done", timeout_s)) return kExitRefused;
  const Value lines = client.get("NozzleCalibration");
  for (std::size_t i = 0; i < lines.size(); ++i)
    std::cout << "nozzle " << i << ": " << text_value("NozzleCalibration", Value::array({lines[i]}))
              << "\n";
  return 0;
}

int run_valve_test(BusClient& client, std::uint32_t nozzle, double duty_pct, double seconds) {
  client.test_valve(nozzle, duty_pct, seconds);
  return follow_calibration(client, "done", seconds + 30.0) ? 0 : kExitRefused;
}

int run_pump_test(BusClient& client, double seconds) {
  client.call("TestPump", "d", seconds);
  return follow_calibration(client, "done", seconds + 30.0) ? 0 : kExitRefused;
}

void print_inputs(std::ostream& out, const Value& inputs, bool json,
                  std::chrono::system_clock::time_point now) {
  if (json) {
    Value object = Value::object();
    for (const auto& input : inputs)
      object[input.value("name", "")] = {{"value", input.value("value", 0.0)},
                                         {"unit", input.value("unit", "")}};
    out << Value{{"RawInputs", object}, {"timestamp", utc_timestamp(now)}}.dump() << "\n";
    return;
  }
  for (const auto& input : inputs) {
    const double value = input.value("value", 0.0);
    out << std::left << std::setw(26) << input.value("name", "") << std::right << std::setw(14);
    if (value == std::floor(value) && std::abs(value) < 1e15)
      out << static_cast<long long>(value);
    else
      out << std::fixed << std::setprecision(3) << value;
    out << "  " << input.value("unit", "") << "\n";
  }
}

}  // namespace weedspray::sprayctl
