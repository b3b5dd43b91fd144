// SPDX-License-Identifier: Apache-2.0
#include "daemon/backends/backends.hpp"

#include "io/linux/gpsd_gnss.hpp"
#include "io/linux/iio_gyro.hpp"

namespace weedspray::daemon {

namespace {

io::DigitalOutputBank* bank(const Backends& b, OutputRole role) noexcept {
  switch (role) {
    case OutputRole::kValves:
      return b.valves;
    case OutputRole::kPump:
      return b.pump;
    case OutputRole::kHeartbeat:
      return b.heartbeat;
    case OutputRole::kBuzzer:
      return b.buzzer;
    case OutputRole::kLed:
      return b.led;
    case OutputRole::kReturnValve:
      return nullptr;
  }
  return nullptr;
}

}  // namespace

int Backends::force_safe(OutputRole role) noexcept {
  if (role == OutputRole::kReturnValve)
    return return_valve != nullptr ? return_valve->force_safe() : 0;
  io::DigitalOutputBank* output = bank(*this, role);
  return output != nullptr ? output->force_safe() : 0;
}

SafeWriteErrors Backends::force_safe() noexcept {
  SafeWriteErrors errors{};
  // Valves and pump first: they move liquid.
  for (OutputRole role : {OutputRole::kValves, OutputRole::kPump, OutputRole::kReturnValve,
                          OutputRole::kBuzzer, OutputRole::kLed, OutputRole::kHeartbeat})
    errors[static_cast<std::size_t>(role)] = force_safe(role);
  return errors;
}

std::array<std::string, kOutputRoleCount> Backends::output_devices() const {
  std::array<std::string, kOutputRoleCount> devices;
  for (std::size_t i = 0; i < kOutputRoleCount; ++i) {
    const auto role = static_cast<OutputRole>(i);
    if (role == OutputRole::kReturnValve) {
      if (return_valve != nullptr) devices[i] = return_valve->describe();
    } else if (const io::DigitalOutputBank* output = bank(*this, role)) {
      devices[i] = output->describe();
    }
  }
  return devices;
}

std::size_t Backends::register_emergency_writes() const noexcept {
  io::EmergencyOutputs::clear();
  std::size_t registered = 0;
  io::EmergencyWrite write;
  for (const io::DigitalOutputBank* bank : {valves, pump, buzzer, led, heartbeat}) {
    if (bank != nullptr && bank->emergency_write(write) && io::EmergencyOutputs::add(write))
      ++registered;
  }
  if (return_valve != nullptr && return_valve->emergency_write(write) &&
      io::EmergencyOutputs::add(write))
    ++registered;
  return registered;
}

io::CurrentLoopSensorConfig pressure_sensor_config(const Config& config) {
  io::CurrentLoopSensorConfig sensor;
  sensor.shunt_ohms = config.adc.shunt_ohms;
  sensor.pressure_at_min_mpa = config.pressure.sensor_min_mpa;
  sensor.pressure_at_max_mpa = config.pressure.sensor_max_mpa;
  sensor.fault_below_ma = config.alarms.sensor_fault_low_ma;
  sensor.fault_above_ma = config.alarms.sensor_fault_high_ma;
  return sensor;
}

io::ValveDriveConfig valve_drive_config(const Config& config) {
  io::ValveDriveConfig drive;
  drive.dac_full_scale_volts = config.dac.full_scale_v;
  drive.amplifier_gain = drive.valve_full_scale_volts / config.dac.full_scale_v;
  drive.opens_at_zero_volts = config.dac.return_valve_open_at == "zero";
  return drive;
}

void add_yaw_sensor(Backends& b, const Config& config) {
  if (config.turn.yaw_source != "imu") return;
  io::hw::IioGyroConfig gyro;
  gyro.device = config.turn.imu_device;
  gyro.axis = config.turn.imu_axis.empty() ? 'z' : config.turn.imu_axis.front();
  gyro.axis_points_up = config.turn.imu_axis_up;
  auto sensor = std::make_shared<io::hw::IioGyro>(gyro);
  b.yaw_sensor = sensor.get();
  b.owned.push_back(sensor);
}

void add_gnss(Backends& b, const Config& config) {
  if (!config.gnss.enabled) return;
  if (config.gnss.source == "fleet") {
    b.gnss_from_fleet = true;
    return;
  }
  io::hw::GpsdGnssConfig gpsd;
  gpsd.host = config.gnss.host;
  gpsd.port = std::to_string(config.gnss.port);
  gpsd.max_retry = std::chrono::milliseconds(static_cast<int>(config.gnss.reconnect_max_s * 1000));
  auto receiver = std::make_shared<io::hw::GpsdGnss>(gpsd);
  b.gnss = receiver.get();
  b.owned.push_back(receiver);
}

}  // namespace weedspray::daemon
