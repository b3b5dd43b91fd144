// SPDX-License-Identifier: Apache-2.0
// The camera's far side: frames written into the kernel's v4l2loopback device, whose capture
// side the daemon opens as its V4L2 camera. The frames are files of raw YUYV (weedspray-lab
// hil-frames: tiles of the bundled field photos); a writer thread shows the current one at a
// fixed rate, and show() switches to another (the scenario's "frame NAME" command).
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace weedspray::hil {

struct LoopbackCameraConfig {
  std::string device;      // v4l2loopback's node, e.g. /dev/video20
  std::string frames_dir;  // NAME.yuyv files, width x height x 2 bytes each
  std::string first_frame;
  int width = 320;
  int height = 180;
  double fps = 2;
};

class LoopbackCamera {
 public:
  // Opens the device, sets the output format, loads every NAME.yuyv and writes the first
  // frame (v4l2loopback with exclusive_caps shows its capture side only once a writer has
  // written). Throws std::runtime_error naming the device or file.
  explicit LoopbackCamera(const LoopbackCameraConfig& config);
  ~LoopbackCamera();
  LoopbackCamera(const LoopbackCamera&) = delete;
  LoopbackCamera& operator=(const LoopbackCamera&) = delete;

  // Shows frame NAME from the next write on; false if there is no such frame.
  bool show(const std::string& name);
  std::string current() const;
  std::uint64_t writes() const { return writes_; }
  std::uint64_t write_errors() const { return write_errors_; }

 private:
  void write_loop();
  bool write_current();

  LoopbackCameraConfig config_;
  int fd_ = -1;
  std::map<std::string, std::vector<std::uint8_t>> frames_;
  mutable std::mutex mutex_;
  std::string current_;
  std::atomic<std::uint64_t> writes_{0};
  std::atomic<std::uint64_t> write_errors_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace weedspray::hil
