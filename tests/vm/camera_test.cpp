// SPDX-License-Identifier: Apache-2.0
// The V4L2 camera (io::hw::V4l2Camera) streaming from the kernel's vivid virtual camera.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "io/linux/monotonic_clock.hpp"
#include "io/linux/v4l2_camera.hpp"
#include "tests/vm/vivid_fixture.hpp"

namespace weedspray::io::hw {
namespace {

using namespace std::chrono_literals;

std::size_t bytes_per_pixel_row(vision::PixelFormat format, int width) {
  switch (format) {
    case vision::PixelFormat::kYuyv:
      return 2 * static_cast<std::size_t>(width);
    case vision::PixelFormat::kGrey:
      return static_cast<std::size_t>(width);
    case vision::PixelFormat::kRgb24:
    case vision::PixelFormat::kBgr24:
      return 3 * static_cast<std::size_t>(width);
  }
  return 0;
}

struct FormatCase {
  CameraPixelFormat requested;
  vision::PixelFormat delivered;
  const char* name;
};

void PrintTo(const FormatCase& format, std::ostream* out) {
  *out << format.name;
}

class CameraStreamTest : public ::testing::TestWithParam<FormatCase> {};

// >= 10 frames through mmap: the right size/format, a real picture (vivid's colour bars are
// not flat), sequence numbers and timestamps increasing, timestamps on CLOCK_MONOTONIC close to
// now, spaced about one frame period per sequence step.
TEST_P(CameraStreamTest, StreamsFramesWithPlausibleTimestamps) {
  constexpr int kFrames = 12;
  constexpr int kFps = 30;
  MonotonicClock clock;
  V4l2CameraConfig config = vm_test::vivid_camera_config(kFps);
  config.pixel_format = GetParam().requested;
  V4l2Camera camera(config, clock);
  ASSERT_TRUE(camera.start()) << camera.last_error();
  EXPECT_EQ(camera.width(), 640);
  EXPECT_EQ(camera.height(), 360);

  std::vector<std::chrono::nanoseconds> timestamps;
  std::vector<std::uint64_t> sequences;
  for (int i = 0; i < kFrames; ++i) {
    Frame frame;
    ASSERT_EQ(camera.next_frame(frame, 3s), FrameStatus::kOk)
        << "frame " << i << ": " << camera.last_error();
    const auto now = monotonic_now();
    EXPECT_LE(frame.timestamp, now) << "frame " << i << " is from the future";
    EXPECT_LT(now - frame.timestamp, 1s) << "frame " << i << " is stale or on another clock";
    EXPECT_EQ(frame.view.width, 640);
    EXPECT_EQ(frame.view.height, 360);
    EXPECT_EQ(frame.view.format, GetParam().delivered);
    const std::size_t row_bytes = bytes_per_pixel_row(frame.view.format, frame.view.width);
    ASSERT_GE(frame.view.stride, row_bytes);
    ASSERT_NE(frame.view.data, nullptr);
    // A whole middle row: vivid's colour bars give several distinct byte values.
    const std::uint8_t* row = frame.view.data + frame.view.stride * (frame.view.height / 2);
    const auto [lowest, highest] = std::minmax_element(row, row + row_bytes);
    EXPECT_GT(*highest - *lowest, 32) << "frame " << i << " looks flat";
    timestamps.push_back(frame.timestamp);
    sequences.push_back(frame.sequence);
  }
  camera.stop();

  std::vector<double> periods_ms;  // time per sequence step
  for (std::size_t i = 1; i < timestamps.size(); ++i) {
    ASSERT_GT(sequences[i], sequences[i - 1]) << "frame " << i;
    ASSERT_GT(timestamps[i], timestamps[i - 1]) << "frame " << i;
    periods_ms.push_back(
        std::chrono::duration<double, std::milli>(timestamps[i] - timestamps[i - 1]).count() /
        static_cast<double>(sequences[i] - sequences[i - 1]));
  }
  std::sort(periods_ms.begin(), periods_ms.end());
  const double median_ms = periods_ms[periods_ms.size() / 2];
  EXPECT_NEAR(median_ms, 1000.0 / kFps, 0.2 * 1000.0 / kFps)
      << "frame spacing does not match " << kFps << " fps";
  const CameraCounters counters = camera.counters();
  EXPECT_GE(counters.frames, static_cast<std::uint64_t>(kFrames));
  EXPECT_EQ(counters.errors, 0U);
}

INSTANTIATE_TEST_SUITE_P(
    Vivid, CameraStreamTest,
    ::testing::Values(FormatCase{CameraPixelFormat::kYuyv, vision::PixelFormat::kYuyv, "Yuyv"},
                      FormatCase{CameraPixelFormat::kGrey, vision::PixelFormat::kGrey, "Grey"},
                      FormatCase{CameraPixelFormat::kRgb24, vision::PixelFormat::kRgb24, "Rgb24"}),
    [](const ::testing::TestParamInfo<FormatCase>& info) { return info.param.name; });

TEST(CameraErrorTest, MissingDeviceIsAClearError) {
  MonotonicClock clock;
  V4l2CameraConfig config;
  config.device = "/dev/video-nonexistent";
  V4l2Camera camera(config, clock);
  EXPECT_FALSE(camera.start());
  EXPECT_THAT(camera.last_error(), ::testing::HasSubstr("/dev/video-nonexistent"));
}

TEST(CameraErrorTest, SizeTheDeviceCannotDeliverIsAClearError) {
  MonotonicClock clock;
  V4l2CameraConfig config;
  config.device = vm_test::vivid_video_node();
  config.width = 1234;  // vivid's webcam input has fixed sizes only
  config.height = 567;
  V4l2Camera camera(config, clock);
  EXPECT_FALSE(camera.start());
  EXPECT_THAT(camera.last_error(), ::testing::HasSubstr("1234"));
}

// vivid has no exposure or white-balance controls: asking for them must say which one failed,
// not stream with a colour balance nobody chose.
TEST(CameraErrorTest, ControlTheDeviceLacksIsAClearError) {
  MonotonicClock clock;
  V4l2CameraConfig config = vm_test::vivid_camera_config();
  config.auto_white_balance = false;
  config.white_balance_temperature = 5000;
  V4l2Camera camera(config, clock);
  EXPECT_FALSE(camera.start());
  EXPECT_THAT(camera.last_error(), ::testing::HasSubstr("white_balance"));
  config.auto_white_balance.reset();
  config.white_balance_temperature.reset();
  config.exposure_absolute = 100;
  V4l2Camera exposed(config, clock);
  EXPECT_FALSE(exposed.start());
  EXPECT_THAT(exposed.last_error(), ::testing::HasSubstr("exposure"));
}

}  // namespace
}  // namespace weedspray::io::hw
