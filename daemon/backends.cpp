#include "daemon/backends.hpp"

namespace weedspray::daemon {

void Backends::force_safe() noexcept {
  if (valves != nullptr) valves->force_safe();
  if (pump != nullptr) pump->force_safe();
  if (return_valve != nullptr) return_valve->force_safe();
  if (buzzer != nullptr) buzzer->force_safe();
  if (led != nullptr) led->force_safe();
  if (heartbeat != nullptr) heartbeat->force_safe();
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
  return drive;
}

}  // namespace weedspray::daemon
