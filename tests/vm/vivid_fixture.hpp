// SPDX-License-Identifier: Apache-2.0
// Test-side access to the vivid camera guest-init.sh sets up: finds its video node and
// "unplugs" it from outside the camera class, the way a cable pulled in the field looks to it.
//
// Unplugging uses vivid's own Disconnect button (error injection, on unless vivid is loaded with
// no_error_inj=1). Its behaviour (drivers/media/test-drivers/vivid, kernel >= 5.11): every node is
// marked unregistered, so open() fails with ENODEV, ioctls fail and poll() reports
// POLLERR|POLLHUP on files already open; vivid registers the nodes again when the LAST open
// file handle of the device is closed. VividDisconnect keeps a handle open while it lives, so
// the device stays gone until reconnect() closes it after the camera has let go of its own.
#pragma once

#include <string>

#include "io/linux/v4l2_camera.hpp"

namespace weedspray::vm_test {

// "/dev/videoN" of the (only) vivid capture node. Throws std::runtime_error when there is none.
std::string vivid_video_node();

// A camera configuration vivid's webcam input can deliver: its node, 640x360 YUYV at `fps`.
io::hw::V4l2CameraConfig vivid_camera_config(int fps = 30);

class VividDisconnect {
 public:
  // Opens `device` and presses Disconnect. Throws std::runtime_error naming the device when it
  // cannot be opened or has no Disconnect control.
  explicit VividDisconnect(const std::string& device);
  ~VividDisconnect();
  VividDisconnect(const VividDisconnect&) = delete;
  VividDisconnect& operator=(const VividDisconnect&) = delete;

  // Closes the held handle: vivid comes back once no one else has the device open. Idempotent.
  void reconnect() noexcept;

 private:
  int fd_ = -1;
};

}  // namespace weedspray::vm_test
