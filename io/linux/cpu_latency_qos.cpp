// SPDX-License-Identifier: Apache-2.0
#include "io/linux/cpu_latency_qos.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <utility>

namespace weedspray::io::hw {

CpuLatencyRequest::CpuLatencyRequest(int max_latency_us, const std::string& path) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd_ < 0) {
    error_ = path + ": " + std::strerror(errno);
    return;
  }
  // The interface takes a binary s32 (or a hex string); the request holds while fd_ is open.
  const std::int32_t value = max_latency_us;
  if (::write(fd_, &value, sizeof value) != static_cast<ssize_t>(sizeof value)) {
    error_ = path + ": write: " + std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
  }
}

CpuLatencyRequest::~CpuLatencyRequest() {
  if (fd_ >= 0) ::close(fd_);
}

CpuLatencyRequest::CpuLatencyRequest(CpuLatencyRequest&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), error_(std::move(other.error_)) {}

CpuLatencyRequest& CpuLatencyRequest::operator=(CpuLatencyRequest&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    error_ = std::move(other.error_);
  }
  return *this;
}

}  // namespace weedspray::io::hw
