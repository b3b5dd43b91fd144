// SPDX-License-Identifier: Apache-2.0
// ADC and DAC through the kernel's IIO sysfs interface (e.g. ADS1115 and MCP4725 on a Pi):
// /sys/bus/iio/devices/iio:deviceN/in_voltageX_raw (+ _scale), out_voltageX_raw (+ _scale).
// Files are opened once at construction; run-time reads/writes are pread/pwrite on open fds.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "io/analog.hpp"
#include "io/clock.hpp"

namespace weedspray::io::hw {

struct IioChannelConfig {
  // "iio:device0", a full directory path, or the device's `name` (e.g. "ads1015", "mcp4725").
  std::string device;
  int channel = 0;
  // Overrides the scale read from sysfs (millivolts per count); 0 = read *_scale.
  double scale_mv_override = 0.0;
  // Root of the IIO device tree (tests point it at a fake tree).
  std::string sysfs_root = "/sys/bus/iio/devices";
};

struct IioAnalogOutputConfig {
  IioChannelConfig channel;
  double full_scale_volts = 3.3;
  double safe_volts = 0.0;  // written by force_safe() and at construction
  // Largest raw count the converter accepts (MCP4725: 12 bits); the kernel refuses more.
  long max_raw = 4095;
};

// A channel's scale: `channel`_scale (e.g. in_anglvel_z_scale), else the shared `shared`_scale
// (in_anglvel_scale). Throws std::runtime_error naming the files (+ missing_hint when neither
// exists).
double read_iio_scale(const std::string& dir, const std::string& channel, const std::string& shared,
                      const std::string& missing_hint = "");

// Finds the device directory for `device` (see IioChannelConfig). Throws std::runtime_error.
std::string resolve_iio_device_dir(const std::string& device, const std::string& sysfs_root);

class IioAnalogInput final : public AnalogInput {
 public:
  // Throws std::runtime_error naming the device/file when it cannot be opened or parsed.
  IioAnalogInput(const IioChannelConfig& config, const Clock& clock);
  ~IioAnalogInput() override;
  IioAnalogInput(const IioAnalogInput&) = delete;
  IioAnalogInput& operator=(const IioAnalogInput&) = delete;

  AnalogSample read() noexcept override;
  double scale_mv() const noexcept { return scale_mv_; }

 private:
  const Clock& clock_;
  int raw_fd_ = -1;
  double scale_mv_ = 1.0;
  std::uint64_t errors_ = 0;
};

class IioAnalogOutput final : public AnalogOutput {
 public:
  // Opens the channel and writes safe_volts. Throws std::runtime_error naming the file.
  explicit IioAnalogOutput(const IioAnalogOutputConfig& config);
  ~IioAnalogOutput() override;  // force_safe()
  IioAnalogOutput(const IioAnalogOutput&) = delete;
  IioAnalogOutput& operator=(const IioAnalogOutput&) = delete;

  int write(double volts) noexcept override;
  int force_safe() noexcept override;
  std::string describe() const override;
  double full_scale_volts() const noexcept override { return config_.full_scale_volts; }
  bool emergency_write(EmergencyWrite& out) const noexcept override;
  std::uint64_t error_count() const noexcept override { return errors_; }

 private:
  IioAnalogOutputConfig config_;
  int raw_fd_ = -1;
  double scale_mv_ = 1.0;
  std::uint64_t errors_ = 0;
};

}  // namespace weedspray::io::hw
