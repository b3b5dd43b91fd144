// SPDX-License-Identifier: Apache-2.0
// A yaw-rate gyro (an IMU's angular rate about the vertical): turn compensation's yaw source
// when the GNSS course is too slow or absent. A read may block on the sensor's bus (I2C/SPI):
// only ever on a worker thread, which publishes each sample for the control loop.
#pragma once

namespace weedspray::io {

struct YawRateSample {
  double deg_per_s = 0;  // clockwise positive seen from above (as a course over ground grows)
  bool ok = false;
};

class YawRateSensor {
 public:
  virtual ~YawRateSensor() = default;
  virtual YawRateSample read() noexcept = 0;
};

}  // namespace weedspray::io
