// SPDX-License-Identifier: Apache-2.0
// Analog input (pressure sensor via I/V resistor and ADC) and analog output (DAC driving the
// proportional return valve through its amplifier). Volts at the converter pins; conversion to
// physical quantities lives in io/signal_conversion.hpp.
#pragma once

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <string>

#include "io/emergency_outputs.hpp"

namespace weedspray::io {

struct AnalogSample {
  double volts = 0.0;
  std::chrono::nanoseconds time{};  // when the sample was taken
  std::uint64_t error_count = 0;    // failed reads since start
  bool ok = false;                  // false: this read failed, `volts` is not a measurement
};

class AnalogInput {
 public:
  virtual ~AnalogInput() = default;
  // Takes one sample. Call it from the loop that owns the converter (one fast read of an
  // already-open file for IIO).
  virtual AnalogSample read() noexcept = 0;
};

class AnalogOutput {
 public:
  virtual ~AnalogOutput() = default;
  // Writes `volts` (clamped to [0, full_scale_volts()]). Returns 0 or -errno.
  virtual int write(double volts) noexcept = 0;
  // Writes the declared safe voltage (return valve fully open = no line pressure), retrying a
  // failed write; returns 0 or -errno as write() does (see DigitalOutputBank::force_safe).
  virtual int force_safe() noexcept = 0;
  // The converter, for alarms and logs ("iio:device1 out_voltage0_raw").
  virtual std::string describe() const { return {}; }
  virtual double full_scale_volts() const noexcept = 0;
  virtual std::uint64_t error_count() const noexcept = 0;
  // The longest an unchanged value may go without being written again: a module with a
  // communication watchdog puts its output safe when no write arrives in time. Zero: a written
  // value holds until the next write.
  virtual std::chrono::nanoseconds rewrite_within() const noexcept { return {}; }
  // See DigitalOutputBank::emergency_write.
  virtual bool emergency_write(EmergencyWrite& /*out*/) const noexcept { return false; }
};

// write(volts) until it succeeds, at most `attempts` times; returns the last result (the
// converters' force_safe()).
inline int write_with_retries(AnalogOutput& output, double volts, int attempts) noexcept {
  int result = -EIO;
  for (int attempt = 0; attempt < attempts && result != 0; ++attempt) result = output.write(volts);
  return result;
}

}  // namespace weedspray::io
