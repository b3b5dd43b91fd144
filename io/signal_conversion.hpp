// SPDX-License-Identifier: Apache-2.0
// The ONE place where electrical signals become physical quantities and back:
//  - pressure sensor: 4-20 mA loop -> I/V resistor -> volts at the ADC -> pressure in MPa, with
//    the fault rule (< 3.6 mA: broken wire, > 21 mA: short) - a fault is never a pressure;
//  - proportional valve: DAC volts (0-3.3 V) -> amplifier -> 0-10 V at the valve -> opening.
#pragma once

#include <algorithm>

namespace weedspray::io {

struct CurrentLoopSensorConfig {
  double shunt_ohms = 165.0;         // I/V resistor: 20 mA -> 3.3 V
  double current_min_ma = 4.0;       // current at the bottom of the measuring range
  double current_max_ma = 20.0;      // current at the top of the range
  double pressure_at_min_mpa = 0.0;  // pressure reported at current_min_ma
  double pressure_at_max_mpa = 1.0;  // pressure reported at current_max_ma
  double fault_below_ma = 3.6;       // broken wire / sensor unpowered
  double fault_above_ma = 21.0;      // short circuit / sensor failure
};

enum class SensorStatus { kOk, kOpenCircuit, kShortCircuit };

struct PressureReading {
  double pressure_mpa = 0.0;  // meaningful only when status == kOk
  double current_ma = 0.0;
  SensorStatus status = SensorStatus::kOpenCircuit;
  bool ok() const noexcept { return status == SensorStatus::kOk; }
};

constexpr double current_ma_from_volts(double volts, const CurrentLoopSensorConfig& c) noexcept {
  return volts / c.shunt_ohms * 1000.0;
}

constexpr double volts_from_current_ma(double current_ma,
                                       const CurrentLoopSensorConfig& c) noexcept {
  return current_ma / 1000.0 * c.shunt_ohms;
}

// Linear between the range ends; currents between the fault limit and the range end (e.g.
// 3.6-4 mA) are valid and map slightly outside [min, max] pressure (zero offset of the sensor).
constexpr PressureReading pressure_from_sensor_volts(double volts,
                                                     const CurrentLoopSensorConfig& c) noexcept {
  PressureReading r;
  r.current_ma = current_ma_from_volts(volts, c);
  if (r.current_ma < c.fault_below_ma) {
    r.status = SensorStatus::kOpenCircuit;
    return r;
  }
  if (r.current_ma > c.fault_above_ma) {
    r.status = SensorStatus::kShortCircuit;
    return r;
  }
  r.status = SensorStatus::kOk;
  const double span_ma = c.current_max_ma - c.current_min_ma;
  r.pressure_mpa = c.pressure_at_min_mpa + (r.current_ma - c.current_min_ma) / span_ma *
                                               (c.pressure_at_max_mpa - c.pressure_at_min_mpa);
  return r;
}

// The inverse (for simulated sensors): the ADC volts a sensor produces at `pressure_mpa`.
constexpr double sensor_volts_from_pressure_mpa(double pressure_mpa,
                                                const CurrentLoopSensorConfig& c) noexcept {
  const double fraction =
      (pressure_mpa - c.pressure_at_min_mpa) / (c.pressure_at_max_mpa - c.pressure_at_min_mpa);
  return volts_from_current_ma(c.current_min_ma + fraction * (c.current_max_ma - c.current_min_ma),
                               c);
}

struct ValveDriveConfig {
  double dac_full_scale_volts = 3.3;     // DAC output range 0..this
  double amplifier_gain = 10.0 / 3.3;    // valve volts per DAC volt
  double valve_full_scale_volts = 10.0;  // control voltage for a fully driven valve
  // A reverse-acting valve: fully open at 0 V, closed at full-scale volts.
  bool opens_at_zero_volts = false;
};

constexpr double valve_volts_from_dac_volts(double dac_volts, const ValveDriveConfig& c) noexcept {
  return std::clamp(dac_volts, 0.0, c.dac_full_scale_volts) * c.amplifier_gain;
}

constexpr double dac_volts_from_valve_volts(double valve_volts,
                                            const ValveDriveConfig& c) noexcept {
  return std::clamp(valve_volts / c.amplifier_gain, 0.0, c.dac_full_scale_volts);
}

// The valve's opening, clamped to [0, 1]: the fraction of its control range (0 = 0 V, 1 =
// full-scale volts), reversed for a valve that opens at 0 V.
constexpr double valve_opening_from_dac_volts(double dac_volts,
                                              const ValveDriveConfig& c) noexcept {
  const double drive =
      std::clamp(valve_volts_from_dac_volts(dac_volts, c) / c.valve_full_scale_volts, 0.0, 1.0);
  return c.opens_at_zero_volts ? 1.0 - drive : drive;
}

constexpr double dac_volts_from_valve_opening(double opening, const ValveDriveConfig& c) noexcept {
  const double clamped = std::clamp(opening, 0.0, 1.0);
  const double drive = c.opens_at_zero_volts ? 1.0 - clamped : clamped;
  return dac_volts_from_valve_volts(drive * c.valve_full_scale_volts, c);
}

}  // namespace weedspray::io
