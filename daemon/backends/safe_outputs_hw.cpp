// SPDX-License-Identifier: Apache-2.0
// The fail-safe writer's work (ExecStopPost after any exit, kill -9 included): every output
// line requested at its safe value and released, and the return-valve DAC's safe value.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "daemon/backends/backends.hpp"
#include "daemon/backends/hw_output_lines.hpp"
#include "daemon/backends/output_manifest.hpp"
#include "io/linux/gpio_lines.hpp"
#include "io/linux/gpio_output_bank.hpp"

namespace weedspray::daemon {

int write_hw_safe_outputs(const Config& config, std::vector<SafeWriteFailure>& failures) {
  const auto& gpio = config.gpio;
  const auto attempt = [&](const char* what, auto&& make) {
    try {
      Backends b;
      make(b);  // requested with the safe values as defaults; released when b goes
      // The request itself wrote the safe values; a refused explicit write is still reported
      // (ExecStopPost's exit status and the journal name the output).
      const SafeWriteErrors refused = b.force_safe();
      for (std::size_t i = 0; i < kOutputRoleCount; ++i) {
        if (refused[i] != 0)
          failures.push_back(
              {std::string(what) + ": safe value not written: " + std::strerror(-refused[i]),
               refused[i] == -EBUSY});
      }
    } catch (const io::hw::GpioLineBusy& error) {
      failures.push_back({std::string(what) + ": " + error.what(), true});
    } catch (const std::exception& error) {
      failures.push_back({std::string(what) + ": " + error.what(), false});
    }
  };
  attempt("valves", [&](Backends& b) {
    io::hw::GpioOutputBankConfig valves;
    valves.chip = gpio.chip;
    valves.consumer = "weedsprayd-safe";
    for (int offset : gpio.valve_offsets)
      valves.lines.push_back(
          {.name = {}, .offset = offset, .active_low = gpio.valve_active_low, .safe_value = false});
    for (const auto& name : gpio.valve_names)
      valves.lines.push_back(
          {.name = name, .offset = -1, .active_low = gpio.valve_active_low, .safe_value = false});
    if (!valves.lines.empty()) b.valves = keep(b, std::make_shared<io::hw::GpioOutputBank>(valves));
  });
  attempt("pump", [&](Backends& b) {
    b.pump = single_line(b, gpio, gpio.pump_name, gpio.pump_offset, gpio.pump_active_low);
  });
  attempt("buzzer", [&](Backends& b) {
    b.buzzer = single_line(b, gpio, gpio.buzzer_name, gpio.buzzer_offset, false);
  });
  attempt("led", [&](Backends& b) {
    b.led = single_line(b, gpio, gpio.led_name, gpio.led_offset, false);
  });
  attempt("heartbeat", [&](Backends& b) {
    b.heartbeat = single_line(b, gpio, gpio.heartbeat_name, gpio.heartbeat_offset, false);
  });
  attempt("return valve", [&](Backends& b) {
    b.return_valve = keep(b, make_hw_return_valve(config));  // writes the safe value when made
  });
  return static_cast<int>(failures.size());
}

int write_safe_outputs(const std::filesystem::path& config_path,
                       const std::filesystem::path& manifest_path, const char* program) {
  const std::optional<Config> config =
      load_safe_outputs_config(config_path, manifest_path, program);
  if (!config) return 1;
  std::vector<SafeWriteFailure> failures;
  write_hw_safe_outputs(*config, failures);
  for (const auto& failure : failures)
    std::fprintf(stderr, "%s: %s\n", program, failure.message.c_str());
  if (failures.empty()) std::printf("%s: outputs written safe\n", program);
  return failures.empty() ? 0 : 1;
}

}  // namespace weedspray::daemon
