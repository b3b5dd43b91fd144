// SPDX-License-Identifier: Apache-2.0
// The board's IIO converters as the plant sees them, through sysfs (/sys/bus/iio/devices/DEV):
// the pressure transmitter's voltage goes into the ADC input `in_voltageN_raw` (written in
// counts; the systemd guest's IIO dummy takes such writes with
// tests/vm/iio_dummy_settable_adc.patch, as an ADS1115's reading follows its input), and the
// return valve's control voltage is what the daemon last wrote to the DAC output
// `out_voltageN_raw`. Both files are opened once; each write or read is one pwrite/pread.
#pragma once

#include <cstdint>
#include <string>

namespace weedspray::hil {

struct IioConvertersConfig {
  std::string device_dir;  // e.g. /sys/bus/iio/devices/iio:device0
  int adc_channel = 0;
  int dac_channel = 0;
  // The daemon's [adc]/[dac] iio_scale_mv: millivolts per count.
  double adc_mv_per_count = 0.125;  // an ADS1115 at +-4.096 V
  double dac_mv_per_count = 1.0;
  long adc_max_count = 32767;  // the ADS1115's positive full scale
};

class IioConverters {
 public:
  // Throws std::runtime_error naming the file that cannot be opened.
  explicit IioConverters(const IioConvertersConfig& config);
  ~IioConverters();
  IioConverters(const IioConverters&) = delete;
  IioConverters& operator=(const IioConverters&) = delete;

  // The ADC input's voltage: written when its count changes (a failed write is counted).
  void set_adc_volts(double volts) noexcept;
  // The DAC output's voltage as the daemon left it (the last good read after a failed one).
  double dac_volts() noexcept;

  long adc_counts() const noexcept { return adc_counts_; }
  std::uint64_t adc_writes() const noexcept { return adc_writes_; }
  std::uint64_t errors() const noexcept { return errors_; }

 private:
  IioConvertersConfig config_;
  int adc_fd_ = -1;
  int dac_fd_ = -1;
  long adc_counts_ = -1;  // the count last written (-1: none yet)
  long dac_counts_ = 0;
  std::uint64_t adc_writes_ = 0;
  std::uint64_t errors_ = 0;
};

}  // namespace weedspray::hil
