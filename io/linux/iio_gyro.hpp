// SPDX-License-Identifier: Apache-2.0
// An IMU's gyro through the kernel's IIO sysfs interface (e.g. MPU-6050 with inv_mpu6050,
// LSM6DS3 with st_lsm6dsx, BMI160 on a Pi's I2C/SPI): in_anglvel_<axis>_raw, scaled by
// in_anglvel_<axis>_scale or in_anglvel_scale (rad/s per count), plus in_anglvel_<axis>_offset
// when the driver has one. IIO's angular rates follow the right-hand rule: about an axis that
// points UP a left (counter-clockwise) turn is positive, so the yaw rate clockwise is its
// negative; a sensor mounted with that axis pointing down sets axis_points_up = false.
// The raw file is opened once; each read is one pread (which may wait on the sensor's bus).
#pragma once

#include <string>

#include "io/yaw_rate_sensor.hpp"

namespace weedspray::io::hw {

struct IioGyroConfig {
  std::string device;  // "iio:device0", a directory, or the device's name ("mpu6050")
  char axis = 'z';     // the sensor axis that is vertical on the machine
  bool axis_points_up = true;
  std::string sysfs_root = "/sys/bus/iio/devices";  // tests point it at a fake tree
};

class IioGyro final : public YawRateSensor {
 public:
  // Throws std::runtime_error naming the device or file when it cannot be opened or parsed.
  explicit IioGyro(const IioGyroConfig& config);
  ~IioGyro() override;
  IioGyro(const IioGyro&) = delete;
  IioGyro& operator=(const IioGyro&) = delete;

  YawRateSample read() noexcept override;

 private:
  int raw_fd_ = -1;
  double deg_per_count_ = 0;  // signed: clockwise yaw per raw count
  double offset_counts_ = 0;
};

}  // namespace weedspray::io::hw
