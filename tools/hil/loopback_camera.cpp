// SPDX-License-Identifier: Apache-2.0
#include "tools/hil/loopback_camera.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>

namespace weedspray::hil {

LoopbackCamera::LoopbackCamera(const LoopbackCameraConfig& config) : config_(config) {
  const std::size_t frame_bytes = static_cast<std::size_t>(config.width) * config.height * 2;
  for (const auto& entry : std::filesystem::directory_iterator(config.frames_dir)) {
    if (entry.path().extension() != ".yuyv") continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                    std::istreambuf_iterator<char>());
    if (bytes.size() != frame_bytes)
      throw std::runtime_error(entry.path().string() + ": " + std::to_string(bytes.size()) +
                               " bytes, a " + std::to_string(config.width) + "x" +
                               std::to_string(config.height) + " YUYV frame has " +
                               std::to_string(frame_bytes));
    frames_[entry.path().stem().string()] = std::move(bytes);
  }
  if (frames_.count(config.first_frame) == 0)
    throw std::runtime_error("no frame '" + config.first_frame + ".yuyv' in " + config.frames_dir);
  current_ = config.first_frame;

  fd_ = ::open(config.device.c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) throw std::runtime_error(config.device + ": " + std::strerror(errno));
  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  format.fmt.pix.width = static_cast<std::uint32_t>(config.width);
  format.fmt.pix.height = static_cast<std::uint32_t>(config.height);
  format.fmt.pix.pixelformat = V4L2_PIX_FMT_YUYV;
  format.fmt.pix.field = V4L2_FIELD_NONE;
  format.fmt.pix.bytesperline = static_cast<std::uint32_t>(config.width) * 2;
  format.fmt.pix.sizeimage = static_cast<std::uint32_t>(frame_bytes);
  if (::ioctl(fd_, VIDIOC_S_FMT, &format) != 0) {
    const int error = errno;
    ::close(fd_);
    throw std::runtime_error(config.device + ": VIDIOC_S_FMT (output, YUYV " +
                             std::to_string(config.width) + "x" + std::to_string(config.height) +
                             "): " + std::strerror(error));
  }
  if (!write_current()) {
    ::close(fd_);
    throw std::runtime_error(config.device + ": writing the first frame failed");
  }
  thread_ = std::thread([this] { write_loop(); });
}

LoopbackCamera::~LoopbackCamera() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (fd_ >= 0) ::close(fd_);
}

bool LoopbackCamera::show(const std::string& name) {
  if (frames_.count(name) == 0) return false;
  std::lock_guard lock(mutex_);
  current_ = name;
  return true;
}

std::string LoopbackCamera::current() const {
  std::lock_guard lock(mutex_);
  return current_;
}

bool LoopbackCamera::write_current() {
  const std::vector<std::uint8_t>* frame = nullptr;
  {
    std::lock_guard lock(mutex_);
    frame = &frames_.at(current_);  // the map does not change after construction
  }
  const bool ok = ::write(fd_, frame->data(), frame->size()) == static_cast<ssize_t>(frame->size());
  ++(ok ? writes_ : write_errors_);
  return ok;
}

void LoopbackCamera::write_loop() {
  // Absolute deadlines: a camera's frames come at its rate, not at the rate minus our work.
  const long period_ns = static_cast<long>(1e9 / config_.fps);
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  while (!stop_) {
    next.tv_nsec += period_ns;
    while (next.tv_nsec >= 1000000000L) {
      next.tv_nsec -= 1000000000L;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    write_current();
  }
}

}  // namespace weedspray::hil
