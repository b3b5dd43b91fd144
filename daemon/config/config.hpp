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

#include "vision/weed_source.hpp"

namespace weedspray::daemon {

struct DaemonSection {
  bool autostart;
  std::string log_level;  // trace|debug|info|warn|error
  std::string state_dir;
  double status_max_rate_hz;     // PropertiesChanged at most this often
  double input_stale_timeout_s;  // any live input older than this -> valves off
  int cpu_wakeup_latency_us;     // PM QoS request while running; -1 = none
};

struct BoomSection {
  int nozzles;
  double nozzle_width_m;
  double valve_open_delay_s;
  double valve_close_delay_s;
};

struct CameraSection {
  std::string device;
  int width;
  int height;
  double fps;
  std::string format;   // YUYV|MJPG|RGB3|GREY
  int exposure_us;      // 0 = automatic
  int white_balance_k;  // 0 = the camera's own setting
  double mount_height_m;
  double tilt_deg;  // optical axis from vertical, looking forward
  double vfov_deg;
  double distance_to_nozzles_m;  // nozzle line behind the camera's nadir
  double ground_mm_per_px;       // 0 = from mount_height_m, tilt_deg, vfov_deg and height
  int first_nozzle;
  int nozzle_count;
};

struct VisionSection {
  std::string index;
  std::string threshold;
  int fixed_threshold;
  int grid_rows;
  std::string weed_source;  // vegetation|inter_row|dnn|hybrid|plants
  double row_band_cm;       // inter_row: width of a crop-row band on the ground
  double crop_margin_cm;    // hybrid: the network's crop mask grown by this much
  double min_plant_cm2;     // plants: smaller connected vegetation is not a plant
  std::string model;        // ONNX file (dnn, hybrid); relative: see resolve_model_path()
  int model_input_width;
  int model_input_height;
  std::vector<double> model_mean;  // R, G, B on the 0..255 scale
  double model_scale;
  bool model_rgb;
  std::vector<std::string> model_classes;
  int soil_class;
  int crop_class;
  int weed_class;
  int max_network_pixels;  // largest network input the ground scale may ask for
};

// The weed model a configuration uses (dnn, hybrid), read once at load: the file found and its
// bytes, which every camera's vision pipeline is built from.
struct LoadedModel {
  std::filesystem::path path;
  std::vector<std::uint8_t> onnx;
  std::filesystem::path description_path;  // NAME.json beside NAME.onnx
  vision::DnnModelSpec spec;       // the JSON's spec with the configuration's overrides applied
  std::string licence;             // as the JSON states it
  double dataset_mm_per_px = 0.0;  // its training photos' ground scale; 0 = not stated
};

struct SpraySection {
  // The dose at full weed cover in L/ha; > 0 sets nominal_flow_l_per_min from it at load.
  double target_rate_l_per_ha;
  double nominal_flow_l_per_min;
  double nominal_speed_m_per_s;
  double max_density;
  double calibration_slope_l_per_min_per_pct;
  double calibration_offset_l_per_min;
  double calibration_pressure_mpa;
  double duty_min_pct;
  double duty_max_pct;
  int quantiser_levels;
  double hysteresis_pct;
  double decision_threshold;
  std::string low_duty_policy;  // "raise_to_min" | "close"
  bool pressure_compensation;
};

struct PwmSection {
  double frequency_hz;
  bool staggered;
  std::string order;  // outer_first|inner_first|left_to_right
  double min_on_s;
  double min_off_s;
  double dead_man_s;
};

struct PressureSection {
  double setpoint_mpa;
  std::string controller;  // fuzzy_pid|pid
  double loop_hz;
  double kp;
  double ki;
  double kd;
  double cp;
  double ci;
  double cd;
  double range_mpa;       // Vmax - Vmin for the fuzzy quantisation
  double sensor_min_mpa;  // pressure at 4 mA
  double sensor_max_mpa;  // pressure at 20 mA
  double output_min;      // return-valve closure 0..1
  double output_max;
};

struct GpioSection {
  std::string chip;
  // Each line is named by offset on `chip` or, when its *_name is not empty, by line name.
  std::vector<int> valve_offsets;  // one per nozzle, boom order; empty = not wired
  std::vector<std::string> valve_names;
  bool valve_active_low;
  int pump_offset;  // -1 = not wired
  std::string pump_name;
  bool pump_active_low;
  int buzzer_offset;
  std::string buzzer_name;
  int led_offset;
  std::string led_name;
  int heartbeat_offset;  // square wave while the valve thread runs (external dead-man relay)
  std::string heartbeat_name;
  double heartbeat_hz;
  bool heartbeat_opt_out;  // hardware mode without a heartbeat output: allowed, warned at start
  int key_offset;
  std::string key_name;
  bool key_active_low;
  int estop_offset;  // normally closed E-stop circuit; -1 = none
  std::string estop_name;
  bool estop_active_low;  // the closed circuit pulls the line low
  bool estop_opt_out;     // hardware mode without an E-stop input: allowed, warned at start
  int flow_offset;
  std::string flow_name;
  int wheel_offset;
  std::string wheel_name;
};

struct AdcSection {
  std::string source;  // iio|modbus
  std::string iio_device;
  int pressure_channel;
  double iio_scale_mv;  // mV per count; 0 = read in_voltageN_scale
  double shunt_ohms;    // I/V resistor of the 4-20 mA loop
  int modbus_slave_id;
  int modbus_register;
  std::string modbus_register_type;  // input|holding
  double modbus_volts_per_count;
};

struct DacSection {
  std::string source;  // iio|modbus
  std::string iio_device;
  int channel;
  double iio_scale_mv;  // mV per count; 0 = read out_voltageN_scale
  double full_scale_v;
  std::string return_valve_open_at;  // full_scale|zero: the DAC output that opens it fully
  int modbus_slave_id;
  int modbus_register;
  double modbus_volts_per_count;
  // The module's own fail-safe on a silent master (ModbusCommWatchdog); -1: none.
  int modbus_comm_timeout_register;
  double modbus_comm_timeout_s;
  double modbus_comm_timeout_counts_per_s;  // the module's unit of that register
  int modbus_safe_value_register;
  int write_failures_tolerated;  // in a row, before output_write_failed
};

// The RS-485 bus of the Modbus analog modules (adc/dac source = "modbus").
struct AnalogModbusSection {
  std::string device;
  int baud;
  std::string parity;  // N|E|O
  double timeout_s;
};

struct FlowSection {
  double pulses_per_litre;
  std::string counter;  // "" = GPIO edge events on gpio.flow_*; else a kernel counter device
};

// Calibrations run from the daemon (sprayctl calibrate nozzles; daemon/sprayer/calibration_run).
struct CalibrationSection {
  std::vector<double> duties_pct;  // the nozzle sweep's duties
  double settle_s;                 // skipped at each point (valve, pressure, meter settling)
  double measure_s;                // counted at each point
  double min_r_squared;            // a nozzle's fit below this: the [spray] line stays in use
  bool full_open;                  // also meter each nozzle held open (its full-open flow)
  double meter_max_change_pct;     // a catch test's K this far off flow.pulses_per_litre: refused
};

// Per-nozzle health from the line meter while spraying (control/nozzle_health.hpp).
struct NozzleHealthSection {
  bool enabled;
  double baseline_s;
  double time_constant_s;
  std::string judge;  // band|cusum
  double alarm_fraction;
  double alarm_hold_s;
  double alarm_threshold;
};

struct WheelSection {
  std::string source;  // pulses|fixed
  double pulses_per_metre;
  double fixed_speed_m_per_s;
};

// How the ground speed is found (daemon/sprayer/ground_speed.hpp).
struct SpeedSection {
  std::string source;       // wheel|gnss|fixed|fleet
  double shared_timeout_s;  // fleet: no sample from the owning board for this long is a loss
};

// The GNSS receiver, read through gpsd.
struct GnssSection {
  bool enabled;
  std::string host;
  int port;
  double lost_fix_timeout_s;   // no usable fix for this long: gnss_fix_lost, speed falls back
  double first_fix_timeout_s;  // after start: the receiver's time to find its first fix
  double reconnect_max_s;      // ceiling of the reconnection backoff while gpsd is away
  // Where the antenna sits relative to the middle of the nozzle line (maps place each
  // nozzle's patch from it): ahead along the direction of travel, and right of the centre.
  double antenna_ahead_of_nozzles_m;
  double antenna_right_of_centre_m;
};

// Turn compensation: on a curve each nozzle moves at its own ground speed
// v_i = v + yaw_rate x lateral offset (daemon/sprayer/turn_speed.hpp).
struct TurnSection {
  bool compensation;
  std::string yaw_source;    // gnss|imu|none
  std::string imu_device;    // IIO gyro: "iio:deviceN", a directory, or its name
  std::string imu_axis;      // x|y|z: the sensor axis that is vertical on the machine
  bool imu_axis_up;          // that axis points up (else down)
  double min_speed_m_per_s;  // below: the course is noise, yaw rate taken as 0
  double yaw_filter_s;       // time constant of the yaw-rate low-pass
};

struct ModbusSection {
  bool enabled;
  std::string device;
  int baud;
  std::string parity;  // N|E|O
  int slave_id;
  int tank_register;
  double tank_scale_pct_per_count;
  double poll_period_s;
  double timeout_s;
};

struct AlarmsSection {
  double over_pressure_mpa;
  double sensor_fault_low_ma;
  double sensor_fault_high_ma;
  double blocked_pressure_mpa;
  double blocked_flow_l_per_min;
  double no_flow_l_per_min;
  double tank_low_pct;
  double tank_empty_pct;
  double modbus_silent_s;
  double camera_stall_s;
  double debounce_s;
  double sensor_fault_hold_s;       // a pressure-sensor fault must last this long to latch
  double timing_tolerance_ms;       // lateness that affects spraying
  int control_overrun_limit;        // such misses per second that raise control_overruns
  double calibration_drift_pct;     // the meter and the calibrated nozzles this far apart ...
  double calibration_drift_hold_s;  // ... for this long raise calibration_drift
  double closed_flow_l_per_min;     // flow above this with every valve closed ...
  double closed_flow_settle_s;      // ... closed this long: flow_with_valves_closed (Fault)
};

struct LogSection {
  std::string dir;  // "" = <daemon.state_dir>/as-applied
  int rotate_bytes;
  int keep_files;
  int min_free_mb;  // under this much free space: records_disk_full
};

struct SimSection {
  std::string speed_profile;  // constant|sine|ramp
  double speed_min_m_per_s;
  double speed_max_m_per_s;
  double speed_period_s;
  std::string images_dir;   // "" = the bundled field images
  double images_mm_per_px;  // 0 = each image is a frame as it is, of unknown ground scale
  int seed;
  double wheel_slip_pct;  // the simulated wheel's slip (calibrate-wheel's truth)
};

// The fleet bridge (weedspray-fleet, a program of its own; the daemon ignores these keys): the
// MQTT broker, the board's name and place on the boom, credentials, TLS, accepted commands.
struct FleetSection {
  bool enabled;
  std::string host;
  int port;
  std::string machine;           // topic level: weedspray/<machine>/<board>/...
  std::string board;             // topic level
  double first_nozzle_offset_m;  // the first nozzle's place along the boom, from its left end
  int keepalive_s;               // the broker marks the board lost after 1.5 x this of silence
  std::string username;          // "" = anonymous
  std::string password_file;     // its first line is the password
  std::string tls_cafile;        // "" = no TLS
  std::string tls_certfile;      // client certificate (with tls_keyfile)
  std::string tls_keyfile;
  std::string commands;        // none|operator|admin: the command kinds taken from the broker
  std::string on_board_lost;   // continue|stop: another board of the machine lost
  std::string on_broker_lost;  // continue|stop: this board's link to the broker lost
  double picture_interval_s;   // camera 0's live-view picture published this often (0 = never)
  double motion_rate_hz;       // this board's speed and distance published this often (0 = never)
  std::string speed_from;      // the board whose motion this board's daemon takes ("" = none)
};

// The cab page (weedspray-cab, a program of its own; the daemon ignores these keys): where it
// listens. It reads the broker named in [fleet].
struct CabSection {
  std::string listen_address;
  int port;
};

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
