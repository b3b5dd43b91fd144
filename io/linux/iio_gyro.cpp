// SPDX-License-Identifier: Apache-2.0
#include "io/linux/iio_gyro.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>

#include "io/linux/iio_analog.hpp"

namespace weedspray::io::hw {

namespace fs = std::filesystem;

IioGyro::IioGyro(const IioGyroConfig& config) {
  if (config.axis != 'x' && config.axis != 'y' && config.axis != 'z')
    throw std::runtime_error(std::string("IIO gyro: axis must be x, y or z, not '") + config.axis +
                             "'");
  const std::string dir = resolve_iio_device_dir(config.device, config.sysfs_root);
  const std::string channel = std::string("in_anglvel_") + config.axis;
  const double rad_per_count = read_iio_scale(dir, channel, "in_anglvel");
  // Counter-clockwise about an up axis is positive in IIO; the daemon's yaw is clockwise.
  const double sign = config.axis_points_up ? -1.0 : 1.0;
  deg_per_count_ = sign * rad_per_count * 180.0 / std::numbers::pi;
  const fs::path offset = fs::path(dir) / (channel + "_offset");
  if (fs::exists(offset)) {
    std::ifstream in(offset);
    std::string text;
    std::getline(in, text);
    char* end = nullptr;
    offset_counts_ = std::strtod(text.c_str(), &end);
    if (text.empty() || end == text.c_str())
      throw std::runtime_error("IIO gyro: cannot parse " + offset.string() + ": '" + text + "'");
  }
  const fs::path raw = fs::path(dir) / (channel + "_raw");
  raw_fd_ = ::open(raw.c_str(), O_RDONLY | O_CLOEXEC);
  if (raw_fd_ < 0)
    throw std::runtime_error("IIO gyro: cannot open " + raw.string() + ": " + std::strerror(errno));
}

IioGyro::~IioGyro() {
  if (raw_fd_ >= 0) ::close(raw_fd_);
}

YawRateSample IioGyro::read() noexcept {
  YawRateSample s;
  char buffer[32];
  // A sysfs attribute is re-read from offset 0 on its open fd: one pread per sample.
  const ssize_t n = ::pread(raw_fd_, buffer, sizeof(buffer) - 1, 0);
  if (n <= 0) return s;
  buffer[n] = '\0';
  char* end = nullptr;
  const long raw = std::strtol(buffer, &end, 10);
  if (end == buffer) return s;
  s.deg_per_s = (static_cast<double>(raw) + offset_counts_) * deg_per_count_;
  s.ok = true;
  return s;
}

}  // namespace weedspray::io::hw
