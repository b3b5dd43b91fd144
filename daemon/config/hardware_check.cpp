// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/hardware_check.hpp"

#include <fstream>
#include <regex>
#include <string>
#include <system_error>

namespace weedspray::daemon {
namespace {

namespace fs = std::filesystem;

class Problems {
 public:
  explicit Problems(const Config& config) : config_(config) {}

  void add(const std::string& key, const std::string& message) {
    problems_.emplace_back(locate(key).file, locate(key).line, key, message);
  }
  void add(const ConfigError& error) { problems_.push_back(error); }
  std::vector<ConfigError> take() { return std::move(problems_); }

 private:
  // The key's own line, else the first key set in its section ("camera[1]" for cameras).
  KeySource locate(const std::string& key) const {
    if (const auto s = config_.sources.find(key); s != config_.sources.end()) return s->second;
    const std::string section = key.substr(0, key.find('.'));
    if (const auto s = config_.sources.find(section); s != config_.sources.end()) return s->second;
    for (const auto& [name, source] : config_.sources) {
      if (name.starts_with(section + ".")) return source;
    }
    return {config_.files.empty() ? "<defaults>" : config_.files.front(), 0};
  }

  const Config& config_;
  std::vector<ConfigError> problems_;
};

bool wired(const std::string& name, int offset) {
  return offset >= 0 || !name.empty();
}

// A configured path under the roots: "/dev/video0" -> roots.dev / "video0".
fs::path under_roots(const std::string& path, const DeviceRoots& roots) {
  for (const auto& [prefix, root] :
       {std::pair{std::string("/dev/"), roots.dev}, std::pair{std::string("/sys/"), roots.sys}}) {
    if (path.starts_with(prefix)) return root / path.substr(prefix.size());
  }
  return path;
}

bool path_exists(const fs::path& path) {
  std::error_code ec;
  return fs::exists(path, ec);
}

void check_device(Problems& problems, const std::string& key, const std::string& path,
                  const DeviceRoots& roots, const char* what) {
  if (!path_exists(under_roots(path, roots)))
    problems.add(key, std::string("no ") + what + " " + path);
}

// libgpiod finds a chip by path, name ("gpiochip0") or number; a label cannot be checked
// without opening the chip, so it is left to the daemon's start.
void check_gpio_chip(Problems& problems, const std::string& chip, const DeviceRoots& roots) {
  static const std::regex kNumber("[0-9]+");
  static const std::regex kName("gpiochip[0-9]+");
  if (chip.starts_with("/")) {
    check_device(problems, "gpio.chip", chip, roots, "GPIO chip");
  } else if (std::regex_match(chip, kNumber)) {
    check_device(problems, "gpio.chip", "/dev/gpiochip" + chip, roots, "GPIO chip");
  } else if (std::regex_match(chip, kName)) {
    check_device(problems, "gpio.chip", "/dev/" + chip, roots, "GPIO chip");
  }
}

void check_converter(Problems& problems, const char* section, const std::string& source,
                     const std::string& iio_device, const Config& config,
                     const DeviceRoots& roots) {
  const std::string prefix(section);
  if (source == "iio") {
    check_device(problems, prefix + ".iio_device", "/sys/bus/iio/devices/" + iio_device, roots,
                 "IIO device");
  } else if (source == "modbus") {
    check_device(problems, "analog_modbus.device", config.analog_modbus.device, roots,
                 "serial port");
  }
}

void check_flow_counter(Problems& problems, const std::string& counter, const DeviceRoots& roots) {
  if (counter.empty()) return;
  if (counter.starts_with("/")) {
    check_device(problems, "flow.counter", counter, roots, "counter directory");
    return;
  }
  const fs::path devices = roots.sys / "bus/counter/devices";
  if (path_exists(devices / counter)) return;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(devices, ec)) {
    std::ifstream name_file(entry.path() / "name");
    std::string name;
    if (std::getline(name_file, name) && name == counter) return;
  }
  problems.add("flow.counter", "no counter " + counter + " under /sys/bus/counter/devices");
}

}  // namespace

std::vector<ConfigError> check_hardware(const Config& config, const DeviceRoots& roots) {
  Problems problems(config);
  const GpioSection& gpio = config.gpio;
  if (gpio.valve_offsets.empty() && gpio.valve_names.empty()) {
    problems.add("gpio.valve_offsets",
                 "no valve lines to drive: set gpio.valve_offsets (line numbers) or "
                 "gpio.valve_names (line names), one per nozzle");
  }
  for (bool (*required)(const Config&) : {&require_heartbeat, &require_estop}) {
    try {
      required(config);
    } catch (const ConfigError& error) {
      problems.add(error);
    }
  }
  if (config.wheel.source == "pulses" && !wired(gpio.wheel_name, gpio.wheel_offset)) {
    problems.add("gpio.wheel_offset",
                 "wheel.source = \"pulses\" needs the wheel sensor's line: gpio.wheel_offset or "
                 "gpio.wheel_name (or wheel.source = \"fixed\")");
  }
  check_gpio_chip(problems, gpio.chip, roots);
  for (std::size_t i = 0; i < config.cameras.size(); ++i) {
    check_device(problems, "camera[" + std::to_string(i) + "].device", config.cameras[i].device,
                 roots, "camera");
  }
  if (config.modbus.enabled) {
    check_device(problems, "modbus.device", config.modbus.device, roots, "serial port");
  }
  check_converter(problems, "adc", config.adc.source, config.adc.iio_device, config, roots);
  check_converter(problems, "dac", config.dac.source, config.dac.iio_device, config, roots);
  check_flow_counter(problems, config.flow.counter, roots);
  return problems.take();
}

}  // namespace weedspray::daemon
