// SPDX-License-Identifier: Apache-2.0
// What config.hpp declares beside the sections: the error type, the safety lines hardware mode
// requires, and where the as-applied logs go.
#include "daemon/config/config.hpp"

#include <string>
#include <vector>

namespace weedspray::daemon {

namespace {

// "file:line: key: message" (no line: "file: ..."; no key: "file:line: message"). append()
// only: GCC 12's -Wrestrict misfires on chains of operator+ here.
std::string located(const std::string& file, int line, const std::string& key,
                    const std::string& message) {
  std::string text = file;
  if (line > 0) text.append(":").append(std::to_string(line));
  text.append(": ");
  if (!key.empty()) text.append(key).append(": ");
  return text.append(message);
}

}  // namespace

ConfigError::ConfigError(std::string file, int line, std::string key, const std::string& message)
    : std::runtime_error(located(file, line, key, message)),
      file_(std::move(file)),
      line_(line),
      key_(std::move(key)) {}

ConfigError ConfigError::listing(const std::vector<ConfigError>& errors) {
  if (errors.size() == 1) return errors.front();
  std::string text;
  for (const auto& error : errors) {
    if (!text.empty()) text += '\n';
    text += error.what();
  }
  const ConfigError& first = errors.front();
  return ConfigError(Preformatted{}, text, first.file(), first.line(), first.key());
}

namespace {

// A safety line hardware mode needs (gpio.NAME_offset or gpio.NAME_name) unless
// gpio.NAME_opt_out: false when wired, true when the opt-out allows the start, else throws
// `message` located at one of its keys that says "none", else at the [gpio] section, else the
// file.
bool require_gpio_line(const Config& config, const std::string& name, int offset,
                       const std::string& line_name, bool opt_out, const std::string& message) {
  if (offset >= 0 || !line_name.empty()) return false;
  if (opt_out) return true;
  const std::string prefix = "gpio." + name;
  for (const std::string& key : {prefix + "_offset", prefix + "_name", prefix + "_opt_out"}) {
    if (const auto s = config.sources.find(key); s != config.sources.end())
      throw ConfigError(s->second.file, s->second.line, key, message);
  }
  for (const auto& [key, source] : config.sources) {
    if (key.starts_with("gpio."))
      throw ConfigError(source.file, source.line, prefix + "_name", message);
  }
  throw ConfigError(config.files.empty() ? "<defaults>" : config.files.front(), 0, prefix + "_name",
                    message);
}

}  // namespace

bool require_heartbeat(const Config& config) {
  const GpioSection& g = config.gpio;
  return require_gpio_line(
      config, "heartbeat", g.heartbeat_offset, g.heartbeat_name, g.heartbeat_opt_out,
      "hardware mode needs a heartbeat output: set gpio.heartbeat_name or "
      "gpio.heartbeat_offset to the line that holds the relay powering valves and pump, or "
      "gpio.heartbeat_opt_out = true to run without one");
}

bool require_estop(const Config& config) {
  const GpioSection& g = config.gpio;
  return require_gpio_line(
      config, "estop", g.estop_offset, g.estop_name, g.estop_opt_out,
      "hardware mode needs an emergency-stop input: set gpio.estop_name or gpio.estop_offset "
      "to the line of the normally closed E-stop circuit, or gpio.estop_opt_out = true to run "
      "without one");
}

std::filesystem::path Config::as_applied_dir() const {
  if (!log.dir.empty()) return log.dir;
  return std::filesystem::path(daemon.state_dir) / "as-applied";
}

}  // namespace weedspray::daemon
