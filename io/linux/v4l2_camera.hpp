// SPDX-License-Identifier: Apache-2.0
// A Camera on V4L2 through libv4l2 (v4l2_open / v4l2_ioctl / v4l2_mmap): configurable size,
// rate and pixel format (YUYV, MJPEG decoded with libjpeg-turbo, RGB24, GREY), mmap streaming, the
// driver's buffer timestamp carried with each frame, exposure / white-balance controls, and
// recovery when the device disappears (reopen with exponential backoff, counted).
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "io/camera.hpp"
#include "io/clock.hpp"

namespace weedspray::io::hw {

enum class CameraPixelFormat { kYuyv, kMjpeg, kRgb24, kGrey };

struct V4l2CameraConfig {
  std::string device = "/dev/video0";
  int width = 1280;
  int height = 800;
  int fps = 30;
  CameraPixelFormat pixel_format = CameraPixelFormat::kYuyv;
  int buffer_count = 4;
  std::optional<int> exposure_absolute;  // V4L2_CID_EXPOSURE_ABSOLUTE (100 us units); unset = auto
  std::optional<bool> auto_white_balance;        // V4L2_CID_AUTO_WHITE_BALANCE; unset = leave
  std::optional<int> white_balance_temperature;  // kelvin, with auto_white_balance = false
  std::chrono::milliseconds reopen_backoff_min{100};
  std::chrono::milliseconds reopen_backoff_max{5000};
};

// Parses "yuyv" / "mjpeg" / "rgb24" / "grey" (case-insensitive). Throws std::invalid_argument.
CameraPixelFormat parse_camera_pixel_format(const std::string& text);

class V4l2Camera final : public Camera {
 public:
  // Only stores the configuration; the device is opened by start(). `clock` times reopen
  // back-off and stamps frames whose driver timestamp is not CLOCK_MONOTONIC.
  V4l2Camera(const V4l2CameraConfig& config, Clock& clock);
  ~V4l2Camera() override;
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  // Opens, negotiates the format (fails with a clear message when the device cannot deliver the
  // configured format, size or frame rate exactly), applies controls, maps buffers, starts
  // streaming.
  bool start() override;
  FrameStatus next_frame(Frame& frame, std::chrono::milliseconds timeout) override;
  void stop() noexcept override;
  std::string last_error() const override;
  CameraCounters counters() const noexcept override;

  // The negotiated size (equal to the configured one once start() succeeded).
  int width() const noexcept;
  int height() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace weedspray::io::hw
