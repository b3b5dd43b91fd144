// SPDX-License-Identifier: Apache-2.0
#include "tools/hil/iio_converters.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace weedspray::hil {
namespace {

int open_attribute(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error("cannot open " + path + ": " + std::strerror(errno));
  return fd;
}

}  // namespace

IioConverters::IioConverters(const IioConvertersConfig& config) : config_(config) {
  adc_fd_ = open_attribute(
      config.device_dir + "/in_voltage" + std::to_string(config.adc_channel) + "_raw", O_WRONLY);
  try {
    dac_fd_ = open_attribute(
        config.device_dir + "/out_voltage" + std::to_string(config.dac_channel) + "_raw", O_RDONLY);
  } catch (...) {
    ::close(adc_fd_);
    throw;
  }
}

IioConverters::~IioConverters() {
  ::close(adc_fd_);
  ::close(dac_fd_);
}

void IioConverters::set_adc_volts(double volts) noexcept {
  const long counts =
      std::clamp(std::lround(volts * 1000.0 / config_.adc_mv_per_count), 0L, config_.adc_max_count);
  if (counts == adc_counts_) return;
  char text[32];
  const int length = std::snprintf(text, sizeof text, "%ld\n", counts);
  if (::pwrite(adc_fd_, text, static_cast<std::size_t>(length), 0) != length) {
    ++errors_;
    return;
  }
  adc_counts_ = counts;
  ++adc_writes_;
}

double IioConverters::dac_volts() noexcept {
  char text[32] = {};
  const ssize_t n = ::pread(dac_fd_, text, sizeof text - 1, 0);
  char* end = nullptr;
  const long counts = n > 0 ? std::strtol(text, &end, 10) : 0;
  if (n <= 0 || end == text)
    ++errors_;
  else
    dac_counts_ = counts;
  return static_cast<double>(dac_counts_) * config_.dac_mv_per_count / 1000.0;
}

}  // namespace weedspray::hil
