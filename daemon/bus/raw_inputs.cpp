// SPDX-License-Identifier: Apache-2.0
#include "daemon/bus/raw_inputs.hpp"

namespace weedspray::daemon {

namespace {
double contact_value(bool on) {
  return on ? 1.0 : 0.0;
}
}  // namespace

std::vector<RawInput> raw_inputs(const Backends& backends, const PressureStatus& pressure,
                                 const io::TankLevelSample& tank) {
  std::vector<RawInput> in;
  // The 4-20 mA loop as the ADC reads it: under ~3.6 mA a cut wire, over ~21 mA a short.
  in.push_back({"pressure_sensor_current", pressure.current_ma, "mA"});
  in.push_back({"pressure_sensor_ok", contact_value(pressure.sensor_ok), "0/1"});
  in.push_back({"pressure", pressure.pressure_mpa, "MPa"});
  in.push_back({"adc_errors", static_cast<double>(pressure.adc_errors), "count"});
  // What the pressure loop writes: the return valve's closure through the DAC, the pump relay.
  in.push_back({"return_valve_closure", pressure.closure, "0..1"});
  in.push_back({"pump_on", contact_value(pressure.pump_on), "0/1"});
  if (backends.flow != nullptr) {
    const io::PulseSnapshot flow = backends.flow->snapshot();
    in.push_back({"flow_pulses", static_cast<double>(flow.count), "pulses"});
    in.push_back({"flow_read_errors", static_cast<double>(flow.error_count), "count"});
  }
  if (backends.wheel != nullptr) {
    const io::PulseSnapshot wheel = backends.wheel->snapshot();
    in.push_back({"wheel_pulses", static_cast<double>(wheel.count), "pulses"});
    in.push_back({"wheel_read_errors", static_cast<double>(wheel.error_count), "count"});
  }
  if (backends.tank != nullptr) {
    in.push_back({"tank_level", tank.level_pct, "%"});
    in.push_back({"tank_read_ok", contact_value(tank.ok), "0/1"});
    in.push_back({"tank_timeouts", static_cast<double>(tank.timeouts), "count"});
    in.push_back({"tank_crc_errors", static_cast<double>(tank.crc_errors), "count"});
  }
  if (backends.estop != nullptr) {
    const io::EstopSample estop = backends.estop->sample();
    in.push_back({"estop_circuit_closed", contact_value(estop.circuit_closed), "0/1"});
    in.push_back({"estop_openings", static_cast<double>(estop.openings), "count"});
  }
  if (backends.key != nullptr) {
    const io::DigitalInputSample key = backends.key->sample();
    in.push_back({"key_pressed", contact_value(key.active), "0/1"});
    in.push_back({"key_changes", static_cast<double>(key.change_count), "count"});
  }
  return in;
}

}  // namespace weedspray::daemon
