// SPDX-License-Identifier: Apache-2.0
#include "tests/vm/vivid_fixture.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace weedspray::vm_test {
namespace {

// vivid's private control ids are not in a uAPI header: find the control by its name.
std::uint32_t find_control(int fd, const std::string& device, const char* name) {
  v4l2_query_ext_ctrl query{};
  query.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  while (ioctl(fd, VIDIOC_QUERY_EXT_CTRL, &query) == 0) {
    if (std::strcmp(query.name, name) == 0) return query.id;
    query.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  throw std::runtime_error(device + " has no '" + name +
                           "' control (not vivid, or vivid loaded with no_error_inj=1)");
}

}  // namespace

std::string vivid_video_node() {
  const std::filesystem::path classes = "/sys/class/video4linux";
  if (std::filesystem::is_directory(classes))
    for (const auto& entry : std::filesystem::directory_iterator(classes)) {
      const std::string node = entry.path().filename();
      std::ifstream name_file(entry.path() / "name");
      std::string name;
      std::getline(name_file, name);
      // vivid's nodes are "vivid-000-vid-cap"; the v4l2loopback node is another camera.
      if (node.rfind("video", 0) == 0 && name.rfind("vivid", 0) == 0) return "/dev/" + node;
    }
  throw std::runtime_error("no video node in " + classes.string() + " (is vivid loaded?)");
}

VividDisconnect::VividDisconnect(const std::string& device) {
  fd_ = open(device.c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) throw std::runtime_error("cannot open " + device + ": " + std::strerror(errno));
  try {
    v4l2_control press{};
    press.id = find_control(fd_, device, "Disconnect");
    press.value = 1;
    if (ioctl(fd_, VIDIOC_S_CTRL, &press) != 0)
      throw std::runtime_error("pressing Disconnect on " + device +
                               " failed: " + std::strerror(errno));
  } catch (...) {
    reconnect();
    throw;
  }
}

VividDisconnect::~VividDisconnect() {
  reconnect();
}

void VividDisconnect::reconnect() noexcept {
  if (fd_ < 0) return;
  close(fd_);
  fd_ = -1;
}

io::hw::V4l2CameraConfig vivid_camera_config(int fps) {
  io::hw::V4l2CameraConfig config;
  config.device = vivid_video_node();
  config.width = 640;
  config.height = 360;
  config.fps = fps;
  config.pixel_format = io::hw::CameraPixelFormat::kYuyv;
  return config;
}

}  // namespace weedspray::vm_test
