// SPDX-License-Identifier: Apache-2.0
// The daemon's configuration: /etc/weedspray/weedspray.toml plus conf.d/*.toml drop-ins,
// parsed once into this immutable, range-checked struct. Every key, with its type, default,
// range, unit and documentation, is declared once in config_schema.cpp; the members below
// carry no defaults of their own (default_config() applies the schema's).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "daemon/config/config_measurement.hpp"
#include "daemon/config/config_operation.hpp"
#include "daemon/config/config_supervision.hpp"
#include "daemon/config/config_wiring.hpp"

namespace weedspray::daemon {

// Where a key's value came from (file and line; line 0 = built-in default).
struct KeySource {
  std::string file;
  int line = 0;
};

struct Config {
  DaemonSection daemon;
  BoomSection boom;
  std::vector<CameraSection> cameras;
  VisionSection vision;
  SpraySection spray;
  PwmSection pwm;
  PressureSection pressure;
  GpioSection gpio;
  AdcSection adc;
  DacSection dac;
  AnalogModbusSection analog_modbus;
  FlowSection flow;
  CalibrationSection calibration;
  NozzleHealthSection nozzle_health;
  WheelSection wheel;
  SpeedSection speed;
  GnssSection gnss;
  TurnSection turn;
  ModbusSection modbus;
  AlarmsSection alarms;
  LogSection log;
  SimSection sim;
  FleetSection fleet;
  CabSection cab;

  std::shared_ptr<const LoadedModel> model;  // null unless vision.weed_source needs one

  std::vector<std::string> files;            // files read, in order
  std::map<std::string, KeySource> sources;  // "pressure.setpoint_mpa" -> where it was set

  // <log.dir>, or <daemon.state_dir>/as-applied when log.dir is empty.
  [[nodiscard]] std::filesystem::path as_applied_dir() const;
};

// A bad configuration: which file, line and key, and what is wrong with it.
class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string file, int line, std::string key, const std::string& message);
  // Every problem of `errors` (not empty) as one error: located at the first, its text one
  // "file:line: key: message" line per problem.
  static ConfigError listing(const std::vector<ConfigError>& errors);
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& key() const { return key_; }

 private:
  struct Preformatted {};
  ConfigError(Preformatted, const std::string& text, std::string file, int line, std::string key)
      : std::runtime_error(text), file_(std::move(file)), line_(line), key_(std::move(key)) {}

  std::string file_;
  int line_;
  std::string key_;
};

// Every key at its documented default, with one camera covering every nozzle.
[[nodiscard]] Config default_config();

// Reads `main_file` and then `<its folder>/conf.d/*.toml` in name order (later files win).
// Throws ConfigError naming the file, line and key of the first problem.
[[nodiscard]] Config load_config(const std::filesystem::path& main_file);

// Hardware mode needs a heartbeat output (gpio.heartbeat_offset or gpio.heartbeat_name): the
// channel outside the process that cuts valves and pump through a relay when the daemon stops
// driving them. Throws ConfigError (file, line, key) when there is none and
// gpio.heartbeat_opt_out is not set; returns true when that opt-out is what allows the start
// (the caller warns).
bool require_heartbeat(const Config& config);
inline constexpr const char* kNoHeartbeatWarning =
    "gpio.heartbeat_opt_out = true: no heartbeat output, so nothing outside this "
    "process cuts valves and pump if it stops driving them";

// Hardware mode needs an emergency-stop input (gpio.estop_offset or gpio.estop_name), likewise:
// throws ConfigError when there is none and gpio.estop_opt_out is not set; returns true when
// that opt-out is what allows the start (the caller warns).
bool require_estop(const Config& config);
inline constexpr const char* kNoEstopWarning =
    "gpio.estop_opt_out = true: no emergency-stop input, so only the machine's own E-stop "
    "wiring (if any) stops valves and pump";

// Same, from in-memory documents (name, text) in order; used by tests and --check-config.
[[nodiscard]] Config load_config_from_strings(
    const std::vector<std::pair<std::string, std::string>>& documents);

// load_config() without the weed source check: no model is read and no vision pipeline built
// (model stays null). For the fail-safe writer, which must start fast and with few libraries.
[[nodiscard]] Config load_config_without_vision(const std::filesystem::path& main_file);

// The effective configuration as TOML (every key, current values), parseable back.
[[nodiscard]] std::string dump_config(const Config& config);

// The most [[camera]] tables one board runs (the sprayer's fixed camera workers).
inline constexpr std::size_t kMaxCameras = 8;
// The largest configuration file (or drop-in) the loader reads.
inline constexpr std::uintmax_t kMaxConfigFileBytes = 1u << 20;

using ConfigPtr = std::shared_ptr<const Config>;

// <sysconfdir>/weedspray/weedspray.toml of the install prefix (default_config_path.cpp).
extern const char* const kDefaultConfigPath;

}  // namespace weedspray::daemon
