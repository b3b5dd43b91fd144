// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/config_rules.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>

namespace weedspray::daemon {

void fail_at_key(const Config& config, const std::string& key, const std::string& message,
                 const std::string& located_by) {
  auto source = config.sources.find(key);
  if (source == config.sources.end()) {
    source = config.sources.find(key.substr(0, key.find('.')));  // "camera[1]"
  }
  if (source == config.sources.end() && !located_by.empty()) {
    source = config.sources.find(located_by);
  }
  if (source == config.sources.end()) {
    throw ConfigError(config.files.empty() ? "<defaults>" : config.files.back(), 0, key, message);
  }
  throw ConfigError(source->second.file, source->second.line, key, message);
}

std::string format_number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

namespace {

// The rules, each judging the whole configuration; fail() throws at the key to blame.
class Rules {
 public:
  explicit Rules(const Config& config) : config_(config) {}

  [[noreturn]] void fail(const std::string& key, const std::string& message,
                         const std::string& located_by = "") const {
    fail_at_key(config_, key, message, located_by);
  }

  // Every GPIO line is used once on its chip: two nozzles on one valve line, the pump on a
  // valve's line, or an input sharing an output's line are refused, naming both keys.
  void validate_gpio_lines_unique() const {
    const auto& g = config_.gpio;
    std::map<std::string, std::string> claimed;  // "offset 3" / "name 'PUMP'" -> key
    const auto claim = [&](const std::string& line, const std::string& key,
                           const std::string& located_by) {
      const auto [it, inserted] = claimed.emplace(line, key);
      if (!inserted) fail(key, line + " is already " + it->second, located_by);
    };
    for (std::size_t i = 0; i < g.valve_offsets.size(); ++i) {
      claim("line " + std::to_string(g.valve_offsets[i]),
            "gpio.valve_offsets[" + std::to_string(i) + "]", "gpio.valve_offsets");
    }
    for (std::size_t i = 0; i < g.valve_names.size(); ++i) {
      claim("line '" + g.valve_names[i] + "'", "gpio.valve_names[" + std::to_string(i) + "]",
            "gpio.valve_names");
    }
    const bool wheel_wired = config_.wheel.source != "fixed";
    for (const auto& [offset, name, what, used] :
         {std::tuple{g.pump_offset, &g.pump_name, "pump", true},
          std::tuple{g.buzzer_offset, &g.buzzer_name, "buzzer", true},
          std::tuple{g.led_offset, &g.led_name, "led", true},
          std::tuple{g.heartbeat_offset, &g.heartbeat_name, "heartbeat", true},
          std::tuple{g.key_offset, &g.key_name, "key", true},
          std::tuple{g.estop_offset, &g.estop_name, "estop", true},
          std::tuple{g.flow_offset, &g.flow_name, "flow", config_.flow.counter.empty()},
          std::tuple{g.wheel_offset, &g.wheel_name, "wheel", wheel_wired}}) {
      if (!used) continue;
      const std::string prefix = std::string("gpio.") + what;
      if (offset >= 0) claim("line " + std::to_string(offset), prefix + "_offset", "");
      if (!name->empty()) claim("line '" + *name + "'", prefix + "_name", "");
    }
  }

  // Rules between keys; the message names the key whose value was set last in a file.
  void validate() const {
    const auto& c = config_;
    if (c.cameras.size() > kMaxCameras) {
      fail("camera[" + std::to_string(kMaxCameras) + "]",
           std::to_string(c.cameras.size()) + " [[camera]] tables: at most " +
               std::to_string(kMaxCameras) + " cameras per board");
    }
    std::vector<int> owner(static_cast<std::size_t>(c.boom.nozzles), -1);
    for (std::size_t i = 0; i < c.cameras.size(); ++i) {
      const auto& camera = c.cameras[i];
      const std::string prefix = "camera[" + std::to_string(i) + "].";
      const int last = camera.first_nozzle + camera.nozzle_count;
      if (last > c.boom.nozzles) {
        fail(prefix + "nozzle_count",
             "nozzles " + std::to_string(camera.first_nozzle) + ".." + std::to_string(last - 1) +
                 " do not exist (boom.nozzles = " + std::to_string(c.boom.nozzles) + ")");
      }
      for (int n = camera.first_nozzle; n < last; ++n) {
        if (owner[static_cast<std::size_t>(n)] >= 0) {
          fail(prefix + "first_nozzle",
               "nozzle " + std::to_string(n) + " is already steered by camera[" +
                   std::to_string(owner[static_cast<std::size_t>(n)]) + "]");
        }
        owner[static_cast<std::size_t>(n)] = static_cast<int>(i);
      }
    }
    if (!c.gpio.valve_offsets.empty() &&
        c.gpio.valve_offsets.size() != static_cast<std::size_t>(c.boom.nozzles)) {
      fail("gpio.valve_offsets",
           std::to_string(c.gpio.valve_offsets.size()) +
               " lines listed for boom.nozzles = " + std::to_string(c.boom.nozzles));
    }
    if (!c.gpio.valve_names.empty() &&
        c.gpio.valve_names.size() != static_cast<std::size_t>(c.boom.nozzles)) {
      fail("gpio.valve_names",
           std::to_string(c.gpio.valve_names.size()) +
               " lines listed for boom.nozzles = " + std::to_string(c.boom.nozzles));
    }
    if (!c.gpio.valve_names.empty() && !c.gpio.valve_offsets.empty()) {
      fail("gpio.valve_names", "name the valve lines by offset or by name, not both");
    }
    for (const auto& [name, offset, key] :
         {std::tuple{&c.gpio.pump_name, c.gpio.pump_offset, "gpio.pump_name"},
          std::tuple{&c.gpio.buzzer_name, c.gpio.buzzer_offset, "gpio.buzzer_name"},
          std::tuple{&c.gpio.led_name, c.gpio.led_offset, "gpio.led_name"},
          std::tuple{&c.gpio.heartbeat_name, c.gpio.heartbeat_offset, "gpio.heartbeat_name"},
          std::tuple{&c.gpio.key_name, c.gpio.key_offset, "gpio.key_name"},
          std::tuple{&c.gpio.estop_name, c.gpio.estop_offset, "gpio.estop_name"},
          std::tuple{&c.gpio.flow_name, c.gpio.flow_offset, "gpio.flow_name"},
          std::tuple{&c.gpio.wheel_name, c.gpio.wheel_offset, "gpio.wheel_name"}}) {
      if (!name->empty() && offset >= 0) {
        fail(key, "set either the line name or its offset, not both");
      }
    }
    validate_gpio_lines_unique();
    if (!c.flow.counter.empty() && (!c.gpio.flow_name.empty() || c.gpio.flow_offset >= 0)) {
      fail("flow.counter",
           "the flow meter is wired either to a GPIO line (gpio.flow_offset / "
           "gpio.flow_name) or to a kernel counter, not both");
    }
    if (c.spray.quantiser_levels == 1) {
      fail("spray.quantiser_levels", "must be 0 (no quantisation) or 2..14");
    }
    for (std::size_t i = 0; i < c.cameras.size(); ++i) {
      const auto& camera = c.cameras[i];
      if (camera.tilt_deg + camera.vfov_deg / 2 >= 89.0) {
        fail("camera[" + std::to_string(i) + "].tilt_deg",
             "tilt_deg + vfov_deg / 2 must stay below 89 (the top of the image sees the horizon)");
      }
    }
    if (c.spray.duty_min_pct >= c.spray.duty_max_pct) {
      fail("spray.duty_max_pct", "must be above spray.duty_min_pct");
    }
    if (c.pwm.min_on_s + c.pwm.min_off_s > 1.0 / c.pwm.frequency_hz) {
      fail("pwm.min_on_s",
           "pwm.min_on_s + pwm.min_off_s (" + format_number(c.pwm.min_on_s + c.pwm.min_off_s) +
               " s) must fit in one PWM period (1 / pwm.frequency_hz = " +
               format_number(1.0 / c.pwm.frequency_hz) + " s)",
           "pwm.min_off_s");
    }
    if (c.nozzle_health.enabled) {
      if (!c.pwm.staggered) {
        fail("nozzle_health.enabled",
             "needs pwm.staggered = true (synchronous phases make the nozzles inseparable)",
             "pwm.staggered");
      }
      if (c.boom.nozzles > 8)
        fail("nozzle_health.enabled", "judges at most 8 nozzles", "boom.nozzles");
      // A phase window (period / nozzles) must outlast the meter's lag behind the commands.
      if (1.0 / (c.pwm.frequency_hz * c.boom.nozzles) < 0.04) {
        fail("nozzle_health.enabled",
             "needs a PWM phase window (1 / (pwm.frequency_hz x boom.nozzles)) of 40 ms or more",
             "pwm.frequency_hz");
      }
    }
    if (c.nozzle_health.recheck &&
        c.nozzle_health.recheck_warn_pct >= c.nozzle_health.recheck_alarm_pct) {
      fail("nozzle_health.recheck_alarm_pct", "must be above nozzle_health.recheck_warn_pct",
           "nozzle_health.recheck_warn_pct");
    }
    const auto& sweep = c.calibration.duties_pct;
    if (sweep.empty() || std::all_of(sweep.begin(), sweep.end(),
                                     [&](double duty) { return duty == sweep.front(); })) {
      fail("calibration.duties_pct", "needs at least 2 different duties (a line through them)");
    }
    if (c.pressure.sensor_min_mpa >= c.pressure.sensor_max_mpa) {
      fail("pressure.sensor_max_mpa", "must be above pressure.sensor_min_mpa");
    }
    if (c.pressure.output_min >= c.pressure.output_max) {
      fail("pressure.output_max", "must be above pressure.output_min");
    }
    validate_trip_limits();
    if (c.pressure.setpoint_mpa >= c.alarms.over_pressure_mpa) {
      fail("pressure.setpoint_mpa", "must be below alarms.over_pressure_mpa (" +
                                        format_number(c.alarms.over_pressure_mpa) + " MPa)");
    }
    if (c.alarms.tank_empty_pct >= c.alarms.tank_low_pct) {
      fail("alarms.tank_empty_pct", "must be below alarms.tank_low_pct");
    }
    validate_analog_modbus();
    if (c.turn.yaw_source == "imu" && c.turn.imu_device.empty()) {
      fail("turn.yaw_source", "\"imu\" needs turn.imu_device (the IIO gyro)", "turn.imu_device");
    }
    if (c.speed.source == "gnss" && !c.gnss.enabled) {
      fail("speed.source", "\"gnss\" needs gnss.enabled = true", "gnss.enabled");
    }
    if (c.gnss.enabled && c.gnss.source == "fleet" && c.speed.source != "fleet") {
      fail("gnss.source", "\"fleet\" needs speed.source = \"fleet\" (the fix comes with the speed)",
           "speed.source");
    }
    if (c.sim.speed_min_m_per_s > c.sim.speed_max_m_per_s) {
      fail("sim.speed_min_m_per_s", "must not exceed sim.speed_max_m_per_s");
    }
    validate_fleet();
  }

  // The fleet bridge's names become MQTT topic levels.
  void validate_fleet() const {
    const auto& f = config_.fleet;
    const auto topic_level_ok = [](const std::string& name) {
      return !name.empty() && std::all_of(name.begin(), name.end(), [](char ch) {
        return std::isalnum(static_cast<unsigned char>(ch)) != 0 || ch == '-' || ch == '_';
      });
    };
    if (config_.speed.source == "fleet" && f.speed_from.empty()) {
      fail("speed.source", "\"fleet\" needs fleet.speed_from (the board that owns the speed)",
           "fleet.speed_from");
    }
    if (!f.speed_from.empty() && f.speed_from == f.board) {
      fail("fleet.speed_from", "names this board itself (fleet.board)");
    }
    if (!f.speed_from.empty() && !topic_level_ok(f.speed_from)) {
      fail("fleet.speed_from", "\"" + f.speed_from + "\": needs letters, digits, '-' or '_' only");
    }
    for (const auto& [key, value] :
         {std::pair{"fleet.machine", &f.machine}, std::pair{"fleet.board", &f.board}}) {
      if (!topic_level_ok(*value)) {
        std::string message = "\"";
        message += *value;
        message += "\": needs letters, digits, '-' or '_' only (a topic level)";
        fail(key, message);
      }
    }
  }

  // Trip limits that a value in range can still defeat. The current floors are the key
  // ranges (sensor_fault_low_ma, sensor_fault_high_ma); here the rules between keys.
  void validate_trip_limits() const {
    const auto& c = config_;
    // A transmitter saturates at its full scale (20.5 mA at most), so a trip at or above the
    // pressure it reads at 20 mA may never come: the pump would run on at full pressure.
    if (c.alarms.over_pressure_mpa >= c.pressure.sensor_max_mpa) {
      const bool trip_set = c.sources.count("alarms.over_pressure_mpa") > 0;
      fail(trip_set ? "alarms.over_pressure_mpa" : "pressure.sensor_max_mpa",
           "alarms.over_pressure_mpa (" + format_number(c.alarms.over_pressure_mpa) +
               " MPa) must be below pressure.sensor_max_mpa (" +
               format_number(c.pressure.sensor_max_mpa) +
               " MPa, the sensor's full scale): a trip the sensor cannot read never comes");
    }
  }

  // The Modbus analog modules share one bus, served by the converters' thread alone.
  void validate_analog_modbus() const {
    const auto& c = config_;
    const bool adc = c.adc.source == "modbus";
    const bool dac = c.dac.source == "modbus";
    if (!adc && !dac) return;
    if (c.modbus.enabled && c.modbus.device == c.analog_modbus.device) {
      fail("analog_modbus.device",
           c.analog_modbus.device +
               " is also the tank sensor's [modbus] port, which another thread polls: give the "
               "analog modules their own port");
    }
    if (adc && dac && c.adc.modbus_slave_id == c.dac.modbus_slave_id &&
        c.adc.modbus_register_type == "holding" && c.adc.modbus_register == c.dac.modbus_register) {
      fail("dac.modbus_register", "is the register the pressure is read from");
    }
    if (dac && c.dac.modbus_comm_timeout_register >= 0) {
      const double counts = c.dac.modbus_comm_timeout_s * c.dac.modbus_comm_timeout_counts_per_s;
      if (counts < 1 || counts > 65535) {
        fail("dac.modbus_comm_timeout_s",
             format_number(c.dac.modbus_comm_timeout_s) + " s is " + format_number(counts) +
                 " counts of dac.modbus_comm_timeout_counts_per_s = " +
                 format_number(c.dac.modbus_comm_timeout_counts_per_s) +
                 ": the register holds 1..65535");
      }
      // The worker rewrites every third of the timeout, at the pressure loop's write slots.
      if (c.dac.modbus_comm_timeout_s < 6.0 / c.pressure.loop_hz) {
        fail("dac.modbus_comm_timeout_s",
             "must be at least 6 periods of pressure.loop_hz = " +
                 format_number(c.pressure.loop_hz) + " (" +
                 format_number(6000.0 / c.pressure.loop_hz) +
                 " ms): the value is rewritten every third of it, at the loop's write slots");
      }
    }
    const int dac_registers[] = {c.dac.modbus_comm_timeout_register,
                                 c.dac.modbus_safe_value_register};
    for (const int reg : dac_registers) {
      if (dac && reg == c.dac.modbus_register) {
        fail("dac.modbus_register",
             "is also the module's communication-timeout or safe-value register");
      }
    }
    // One RTU transaction: 8-byte request + 7-byte answer + two 3.5-character silences, 11 bits
    // a character. The converters' thread reads at most half a loop period ahead.
    const double transaction_s = 22.0 * 11.0 / c.analog_modbus.baud;
    const double budget_s = 0.5 / c.pressure.loop_hz;
    if (transaction_s > budget_s) {
      fail("analog_modbus.baud",
           std::to_string(c.analog_modbus.baud) + " baud needs about " +
               format_number(transaction_s * 1e3) + " ms a transaction; pressure.loop_hz = " +
               format_number(c.pressure.loop_hz) + " leaves " + format_number(budget_s * 1e3) +
               " ms: raise the baud rate or lower pressure.loop_hz");
    }
  }

 private:
  const Config& config_;
};

}  // namespace

void check_config_rules(const Config& config) {
  Rules(config).validate();
}

}  // namespace weedspray::daemon
