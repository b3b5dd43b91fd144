// SPDX-License-Identifier: Apache-2.0
// The V4L2 camera (io::hw::V4l2Camera) losing its device while streaming and getting it back:
// vivid is "unplugged" with its Disconnect control (see vivid_fixture.hpp) and plugged back.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <iostream>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "io/linux/monotonic_clock.hpp"
#include "io/linux/v4l2_camera.hpp"
#include "tests/vm/vivid_fixture.hpp"

namespace weedspray::io {

// gtest prints FrameStatus by name in failure messages (found by ADL; internal linkage).
static void PrintTo(FrameStatus status, std::ostream* out) {
  switch (status) {
    case FrameStatus::kOk:
      *out << "kOk";
      return;
    case FrameStatus::kTimeout:
      *out << "kTimeout";
      return;
    case FrameStatus::kError:
      *out << "kError";
      return;
    case FrameStatus::kEnd:
      *out << "kEnd";
      return;
  }
  *out << "FrameStatus(" << static_cast<int>(status) << ")";
}

namespace hw {
namespace {

using namespace std::chrono_literals;
using std::chrono::nanoseconds;

double to_ms(nanoseconds duration) {
  return std::chrono::duration<double, std::milli>(duration).count();
}

// Streams, loses the device for a while, gets it back: while it is gone every next_frame()
// reports an error within its timeout (no frame, no hang, no crash); once it is back the camera
// reopens by itself (counted once) and delivers fresh frames with plausible sequence numbers and
// timestamps again.
TEST(CameraRecoveryTest, ReportsErrorsWhileUnpluggedThenStreamsAgain) {
  constexpr int kFps = 30;
  constexpr int kFramesBefore = 5;
  constexpr int kFramesAfter = 10;
  constexpr auto kCallTimeout = 200ms;
  constexpr auto kUnpluggedFor = 1500ms;  // several reopen attempts at the back-off below
  // A call must return near its timeout; the slack covers the emulated (TCG) guest.
  constexpr auto kHangSlack = 1s;

  MonotonicClock clock;
  V4l2CameraConfig config = vm_test::vivid_camera_config(kFps);
  config.reopen_backoff_min = 50ms;
  config.reopen_backoff_max = 400ms;
  // Declared before the camera so that, should an assertion end the test while unplugged, the
  // camera lets go of the device first and this then brings vivid back for the tests after.
  std::optional<vm_test::VividDisconnect> unplugged;
  V4l2Camera camera(config, clock);
  ASSERT_TRUE(camera.start()) << camera.last_error();

  Frame frame;
  nanoseconds last_timestamp_before{};
  std::uint64_t last_sequence_before = 0;
  for (int i = 0; i < kFramesBefore; ++i) {
    ASSERT_EQ(camera.next_frame(frame, 3s), FrameStatus::kOk)
        << "frame " << i << " before unplugging: " << camera.last_error();
    last_timestamp_before = frame.timestamp;
    last_sequence_before = frame.sequence;
  }

  unplugged.emplace(config.device);
  const nanoseconds unplugged_at = monotonic_now();
  int calls_while_gone = 0;
  while (monotonic_now() - unplugged_at < kUnpluggedFor) {
    const nanoseconds called_at = monotonic_now();
    const FrameStatus status = camera.next_frame(frame, kCallTimeout);
    const nanoseconds took = monotonic_now() - called_at;
    ++calls_while_gone;
    ASSERT_EQ(status, FrameStatus::kError) << "call " << calls_while_gone << " while unplugged";
    ASSERT_LT(took, kCallTimeout + kHangSlack)
        << "call " << calls_while_gone << " blocked " << to_ms(took) << " ms while unplugged";
  }
  EXPECT_THAT(camera.last_error(), ::testing::HasSubstr(config.device));
  const std::string error_while_gone = camera.last_error();
  CameraCounters counters = camera.counters();
  EXPECT_GE(counters.errors, 1U);
  EXPECT_EQ(counters.reopens, 0U) << "reopened a device that is gone";
  EXPECT_EQ(counters.frames, static_cast<std::uint64_t>(kFramesBefore));

  unplugged->reconnect();
  const nanoseconds plugged_at = monotonic_now();
  // Back within one maximum back-off plus stream start-up; 5 s is far beyond both.
  FrameStatus status = FrameStatus::kError;
  while (status != FrameStatus::kOk && monotonic_now() - plugged_at < 5s)
    status = camera.next_frame(frame, 500ms);
  ASSERT_EQ(status, FrameStatus::kOk)
      << "no frame within 5 s of plugging back: " << camera.last_error();
  const nanoseconds back_after = monotonic_now() - plugged_at;

  std::vector<nanoseconds> timestamps;
  std::vector<std::uint64_t> sequences;
  for (int i = 0; i < kFramesAfter; ++i) {
    if (i > 0) {
      ASSERT_EQ(camera.next_frame(frame, 3s), FrameStatus::kOk)
          << "frame " << i << " after plugging back: " << camera.last_error();
    }
    const nanoseconds now = monotonic_now();
    // Exposed after the device came back: not a stale buffer from before the unplugging.
    EXPECT_GT(frame.timestamp, plugged_at) << "frame " << i << " after plugging back";
    EXPECT_LE(frame.timestamp, now) << "frame " << i << " is from the future";
    EXPECT_LT(now - frame.timestamp, 1s) << "frame " << i << " is stale or on another clock";
    EXPECT_EQ(frame.view.width, 640);
    EXPECT_EQ(frame.view.height, 360);
    ASSERT_NE(frame.view.data, nullptr);
    timestamps.push_back(frame.timestamp);
    sequences.push_back(frame.sequence);
  }
  camera.stop();

  // The driver restarts its numbering after a reopen; the camera keeps Frame::sequence rising.
  EXPECT_GT(sequences.front(), last_sequence_before) << "sequence went backwards across the reopen";
  std::vector<double> periods_ms;  // time per sequence step
  for (std::size_t i = 1; i < timestamps.size(); ++i) {
    ASSERT_GT(sequences[i], sequences[i - 1]) << "frame " << i << " after plugging back";
    ASSERT_GT(timestamps[i], timestamps[i - 1]) << "frame " << i << " after plugging back";
    periods_ms.push_back(to_ms(timestamps[i] - timestamps[i - 1]) /
                         static_cast<double>(sequences[i] - sequences[i - 1]));
  }
  std::sort(periods_ms.begin(), periods_ms.end());
  EXPECT_NEAR(periods_ms[periods_ms.size() / 2], 1000.0 / kFps, 0.2 * 1000.0 / kFps)
      << "frame spacing after recovery does not match " << kFps << " fps";

  counters = camera.counters();
  EXPECT_EQ(counters.reopens, 1U) << "one unplugging, one recovery";
  EXPECT_EQ(counters.frames, static_cast<std::uint64_t>(kFramesBefore + kFramesAfter));

  // For the log: what a consumer sees across the gap.
  std::cout << "camera recovery: unplugged " << to_ms(kUnpluggedFor) << " ms, " << calls_while_gone
            << " next_frame() calls all kError (\"" << error_while_gone << "\"), first frame "
            << to_ms(back_after) << " ms after plugging back; sequence " << last_sequence_before
            << " -> " << sequences.front() << ", timestamps "
            << to_ms(timestamps.front() - last_timestamp_before) << " ms apart; counters: frames "
            << counters.frames << " errors " << counters.errors << " timeouts " << counters.timeouts
            << " reopens " << counters.reopens << " dropped " << counters.dropped << "\n";
}

}  // namespace
}  // namespace hw
}  // namespace weedspray::io
