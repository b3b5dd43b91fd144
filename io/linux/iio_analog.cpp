// SPDX-License-Identifier: Apache-2.0
#include "io/linux/iio_analog.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "io/linux/sysfs_text.hpp"

namespace weedspray::io::hw {

namespace fs = std::filesystem;

namespace {

// Scale in millivolts per count: the channel's own _scale, else the shared one.
double read_scale_mv(const fs::path& dir, const std::string& prefix, int channel) {
  return read_iio_scale(dir.string(), prefix + std::to_string(channel), prefix,
                        " (set scale_mv_override)");
}

int open_attribute(const fs::path& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0)
    throw std::runtime_error("IIO: cannot open " + path.string() + ": " + std::strerror(errno));
  return fd;
}

}  // namespace

double read_iio_scale(const std::string& dir, const std::string& channel, const std::string& shared,
                      const std::string& missing_hint) {
  for (const fs::path& p :
       {fs::path(dir) / (channel + "_scale"), fs::path(dir) / (shared + "_scale")}) {
    if (!fs::exists(p)) continue;
    const std::string text = read_first_line(p);
    char* end = nullptr;
    const double scale = std::strtod(text.c_str(), &end);
    if (text.empty() || end == text.c_str() || !(scale > 0.0) || !std::isfinite(scale))
      throw std::runtime_error("IIO: cannot parse a positive scale from " + p.string() + ": '" +
                               text + "'");
    return scale;
  }
  throw std::runtime_error("IIO: no " + channel + "_scale or " + shared + "_scale in " + dir +
                           missing_hint);
}

std::string resolve_iio_device_dir(const std::string& device, const std::string& sysfs_root) {
  if (device.empty()) throw std::runtime_error("IIO: no device configured");
  if (device.front() == '/') {
    if (!fs::is_directory(device)) throw std::runtime_error("IIO: no device directory " + device);
    return device;
  }
  const fs::path direct = fs::path(sysfs_root) / device;
  if (fs::is_directory(direct)) return direct.string();
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(sysfs_root, ec)) {
    if (read_first_line(entry.path() / "name") == device) return entry.path().string();
  }
  throw std::runtime_error("IIO: device '" + device + "' not found under " + sysfs_root +
                           " (neither a directory nor a device name)");
}

IioAnalogInput::IioAnalogInput(const IioChannelConfig& config, const Clock& clock) : clock_(clock) {
  const fs::path dir = resolve_iio_device_dir(config.device, config.sysfs_root);
  scale_mv_ = config.scale_mv_override > 0.0 ? config.scale_mv_override
                                             : read_scale_mv(dir, "in_voltage", config.channel);
  raw_fd_ =
      open_attribute(dir / ("in_voltage" + std::to_string(config.channel) + "_raw"), O_RDONLY);
}

IioAnalogInput::~IioAnalogInput() {
  if (raw_fd_ >= 0) ::close(raw_fd_);
}

AnalogSample IioAnalogInput::read() noexcept {
  AnalogSample s;
  char buffer[32];
  // sysfs attributes are re-read from offset 0 on the open fd: one pread per sample.
  const ssize_t n = ::pread(raw_fd_, buffer, sizeof(buffer) - 1, 0);
  s.time = clock_.now();
  if (n <= 0) {
    ++errors_;
  } else {
    buffer[n] = '\0';
    char* end = nullptr;
    const long raw = std::strtol(buffer, &end, 10);
    if (end == buffer) {
      ++errors_;
    } else {
      s.volts = static_cast<double>(raw) * scale_mv_ / 1000.0;
      s.ok = true;
    }
  }
  s.error_count = errors_;
  return s;
}

IioAnalogOutput::IioAnalogOutput(const IioAnalogOutputConfig& config) : config_(config) {
  const IioChannelConfig& c = config.channel;
  const fs::path dir = resolve_iio_device_dir(c.device, c.sysfs_root);
  scale_mv_ = c.scale_mv_override > 0.0 ? c.scale_mv_override
                                        : read_scale_mv(dir, "out_voltage", c.channel);
  raw_fd_ = open_attribute(dir / ("out_voltage" + std::to_string(c.channel) + "_raw"), O_WRONLY);
  if (write(config.safe_volts) != 0)
    throw std::runtime_error("IIO: writing the safe value to " + dir.string() + "/out_voltage" +
                             std::to_string(c.channel) + "_raw failed");
}

IioAnalogOutput::~IioAnalogOutput() {
  force_safe();
  if (raw_fd_ >= 0) ::close(raw_fd_);
}

int IioAnalogOutput::write(double volts) noexcept {
  // Once a fatal-exit handler has written the safe value, no write may replace it.
  const EmergencyOutputs::OrdinaryWrite gate;
  const double wanted = gate.allowed() && std::isfinite(volts) ? volts : config_.safe_volts;
  const double clamped = std::clamp(wanted, 0.0, config_.full_scale_volts);
  const long raw = std::clamp(std::lround(clamped * 1000.0 / scale_mv_), 0L, config_.max_raw);
  char buffer[32];
  const int len = std::snprintf(buffer, sizeof(buffer), "%ld\n", raw);
  if (::pwrite(raw_fd_, buffer, static_cast<std::size_t>(len), 0) != len) {
    ++errors_;
    return errno != 0 ? -errno : -EIO;
  }
  if (gate.closed_since_entry()) return force_safe();
  return 0;
}

int IioAnalogOutput::force_safe() noexcept {
  return write_with_retries(*this, config_.safe_volts, 3);
}

std::string IioAnalogOutput::describe() const {
  return "IIO " + config_.channel.device + " out_voltage" +
         std::to_string(config_.channel.channel) + "_raw";
}

bool IioAnalogOutput::emergency_write(EmergencyWrite& out) const noexcept {
  const long raw =
      std::clamp(std::lround(config_.safe_volts * 1000.0 / scale_mv_), 0L, config_.max_raw);
  char buffer[32];
  const int len = std::snprintf(buffer, sizeof(buffer), "%ld\n", raw);
  if (raw_fd_ < 0 || len <= 0) return false;
  out = EmergencyWrite{};
  out.kind = EmergencyWrite::Kind::kPwrite;
  out.fd = raw_fd_;
  std::copy(buffer, buffer + len, out.payload.begin());
  out.length = static_cast<std::size_t>(len);
  return true;
}

}  // namespace weedspray::io::hw
