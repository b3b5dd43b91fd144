// SPDX-License-Identifier: Apache-2.0
// The V4L2 camera (io::hw::V4l2Camera) reading frames a writer puts into the kernel's
// v4l2loopback device (/dev/video20, guest-init.sh): the path the systemd guest uses to show the
// daemon real field images. The writer is this test: YUYV 320x180, left half a plant's green,
// right half soil's brown; the camera must deliver exactly those pixels.
#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <thread>
#include <vector>

#include "io/linux/monotonic_clock.hpp"
#include "io/linux/v4l2_camera.hpp"

namespace weedspray::io::hw {
namespace {

using namespace std::chrono_literals;

constexpr const char* kLoopback = "/dev/video20";
constexpr int kWidth = 320;
constexpr int kHeight = 180;
// YUYV (BT.601) of a leaf green and a soil brown.
constexpr std::uint8_t kGreenY = 110, kGreenU = 90, kGreenV = 100;
constexpr std::uint8_t kSoilY = 100, kSoilU = 115, kSoilV = 145;

std::vector<std::uint8_t> field_frame() {
  std::vector<std::uint8_t> frame(static_cast<std::size_t>(kWidth) * kHeight * 2);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; x += 2) {
      const bool plant = x < kWidth / 2;
      std::uint8_t* p = frame.data() + (static_cast<std::size_t>(y) * kWidth + x) * 2;
      p[0] = plant ? kGreenY : kSoilY;
      p[1] = plant ? kGreenU : kSoilU;
      p[2] = plant ? kGreenY : kSoilY;
      p[3] = plant ? kGreenV : kSoilV;
    }
  return frame;
}

// Opens the loopback's output side, sets the format and writes a frame every 50 ms until told.
class LoopbackWriter {
 public:
  LoopbackWriter() {
    fd_ = ::open(kLoopback, O_RDWR | O_CLOEXEC);
    if (fd_ < 0) return;
    v4l2_format format{};
    format.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    format.fmt.pix.width = kWidth;
    format.fmt.pix.height = kHeight;
    format.fmt.pix.pixelformat = V4L2_PIX_FMT_YUYV;
    format.fmt.pix.field = V4L2_FIELD_NONE;
    format.fmt.pix.bytesperline = kWidth * 2;
    format.fmt.pix.sizeimage = kWidth * kHeight * 2;
    if (::ioctl(fd_, VIDIOC_S_FMT, &format) != 0) {
      ::close(fd_);
      fd_ = -1;
      return;
    }
    const std::vector<std::uint8_t> frame = field_frame();
    // One frame before the camera opens: exclusive_caps shows the capture side only then.
    ok_ = ::write(fd_, frame.data(), frame.size()) == static_cast<ssize_t>(frame.size());
    thread_ = std::thread([this, frame] {
      while (!stop_) {
        if (::write(fd_, frame.data(), frame.size()) != static_cast<ssize_t>(frame.size()))
          ok_ = false;
        std::this_thread::sleep_for(50ms);
      }
    });
  }
  ~LoopbackWriter() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    if (fd_ >= 0) ::close(fd_);
  }
  bool ok() const { return fd_ >= 0 && ok_; }

 private:
  int fd_ = -1;
  std::atomic<bool> ok_{false};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST(CameraLoopbackTest, DeliversTheFramesWrittenIntoTheLoopback) {
  if (!std::filesystem::exists(kLoopback)) GTEST_SKIP() << kLoopback << " missing (arm64 guest)";
  LoopbackWriter writer;
  ASSERT_TRUE(writer.ok()) << "writing frames into " << kLoopback << " failed";
  MonotonicClock clock;
  V4l2CameraConfig config;
  config.device = kLoopback;
  config.width = kWidth;
  config.height = kHeight;
  config.fps = 20;
  config.pixel_format = CameraPixelFormat::kYuyv;
  V4l2Camera camera(config, clock);
  ASSERT_TRUE(camera.start()) << camera.last_error();
  for (int i = 0; i < 5; ++i) {
    Frame frame;
    ASSERT_EQ(camera.next_frame(frame, 3s), FrameStatus::kOk)
        << "frame " << i << ": " << camera.last_error();
    ASSERT_EQ(frame.view.width, kWidth);
    ASSERT_EQ(frame.view.height, kHeight);
    ASSERT_EQ(frame.view.format, vision::PixelFormat::kYuyv);
    const std::uint8_t* row = frame.view.data + frame.view.stride * (kHeight / 2);
    // A plant pixel pair on the left, a soil pair on the right, byte for byte.
    const std::uint8_t* left = row + 40 * 2;
    const std::uint8_t* right = row + (kWidth - 40) * 2;
    EXPECT_EQ(left[1], kGreenU) << "frame " << i;
    EXPECT_EQ(left[3], kGreenV) << "frame " << i;
    EXPECT_EQ(right[1], kSoilU) << "frame " << i;
    EXPECT_EQ(right[3], kSoilV) << "frame " << i;
  }
}

}  // namespace
}  // namespace weedspray::io::hw
