// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/snapshot_handoff.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <vector>

#include "daemon/bus/rate_limit.hpp"
#include "tests/unit/vision/allocation_counter.hpp"
#include "vision/weed_source.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

// A soil frame with a green block, rows padded as a camera's may be.
struct Frame {
  static constexpr int kWidth = 64;
  static constexpr int kHeight = 32;
  static constexpr std::size_t kStride = kWidth * 3 + 16;
  std::vector<std::uint8_t> bytes = std::vector<std::uint8_t>(kStride * kHeight, 0);
  Frame() {
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        const bool plant = x >= 40 && x < 56 && y >= 8 && y < 24;
        std::uint8_t* p = &bytes[y * kStride + x * 3];
        p[0] = plant ? 40 : 70;
        p[1] = plant ? 150 : 100;
        p[2] = plant ? 60 : 130;
      }
    }
  }
  vision::ImageView view() const {
    return {bytes.data(), kWidth, kHeight, kStride, vision::PixelFormat::kBgr24};
  }
};

class SnapshotHandoffTest : public ::testing::Test {
 protected:
  SnapshotHandoffTest() : pipeline_(vision::default_pipeline_config()) {
    result_ = &pipeline_.process(frame_.view());
  }
  void fill() { handoff_.fill(frame_.view(), 5s, pipeline_, *result_); }

  Frame frame_;
  vision::Pipeline pipeline_;
  const vision::FrameResult* result_ = nullptr;
  SnapshotHandoff handoff_;
};

TEST_F(SnapshotHandoffTest, NothingIsCopiedUntilAsked) {
  EXPECT_FALSE(handoff_.wanted());
  fill();
  EXPECT_EQ(handoff_.ready(), nullptr);
}

TEST_F(SnapshotHandoffTest, AnAskedFrameArrivesPackedWithItsClassesAndDensities) {
  ASSERT_TRUE(
      handoff_.request(SnapshotHandoff::packed_bytes(frame_.view()), pipeline_.class_map_pixels()));
  EXPECT_TRUE(handoff_.wanted());
  EXPECT_EQ(handoff_.ready(), nullptr) << "ready before the camera thread filled it";
  EXPECT_FALSE(handoff_.request(1, 1)) << "a second request while one is outstanding";
  const long before = test::allocation_count();
  fill();
  EXPECT_EQ(test::allocation_count(), before) << "the camera thread allocated";
  EXPECT_FALSE(handoff_.wanted());
  const SnapshotHandoff::Capture* capture = handoff_.ready();
  ASSERT_NE(capture, nullptr);
  EXPECT_EQ(capture->error, nullptr);
  EXPECT_EQ(capture->capture_time, 5s);
  ASSERT_EQ(capture->frame.width, Frame::kWidth);
  ASSERT_EQ(capture->frame.stride, static_cast<std::size_t>(Frame::kWidth) * 3);
  for (int y = 0; y < Frame::kHeight; ++y) {
    EXPECT_EQ(std::memcmp(capture->frame.data + y * capture->frame.stride,
                          frame_.bytes.data() + y * Frame::kStride, Frame::kWidth * 3),
              0)
        << "row " << y;
  }
  ASSERT_EQ(capture->classes.width, Frame::kWidth);
  EXPECT_EQ(capture->classes.data[16 * Frame::kWidth + 48], vision::kClassWeed);
  EXPECT_EQ(capture->classes.data[16 * Frame::kWidth + 10], vision::kClassSoil);
  EXPECT_EQ(capture->cols, result_->cols);
  EXPECT_DOUBLE_EQ(capture->density[3], result_->zone_density[3]);
  EXPECT_GT(capture->density[3], 0.2);
  // Released: the next frame is not copied until asked again.
  EXPECT_TRUE(handoff_.release());
  EXPECT_EQ(handoff_.ready(), nullptr);
  fill();
  EXPECT_EQ(handoff_.ready(), nullptr);
}

TEST_F(SnapshotHandoffTest, AFrameLargerThanTheBufferIsAnErrorNotAnOverflow) {
  ASSERT_TRUE(handoff_.request(100, pipeline_.class_map_pixels()));
  fill();
  const SnapshotHandoff::Capture* capture = handoff_.ready();
  ASSERT_NE(capture, nullptr);
  ASSERT_NE(capture->error, nullptr);
  EXPECT_NE(std::string(capture->error).find("ask again"), std::string::npos);
}

TEST_F(SnapshotHandoffTest, AGivenUpRequestIsNotFilledLater) {
  ASSERT_TRUE(
      handoff_.request(SnapshotHandoff::packed_bytes(frame_.view()), pipeline_.class_map_pixels()));
  EXPECT_TRUE(handoff_.release());  // the main thread timed out
  EXPECT_FALSE(handoff_.wanted());
  fill();
  EXPECT_EQ(handoff_.ready(), nullptr);
  EXPECT_TRUE(handoff_.request(1, 1)) << "a new request after giving up";
}

TEST(RateLimit, OneIntervalFromTheLastMarkAndARefusalMarksNothing) {
  RateLimit limit(500ms);
  std::chrono::nanoseconds wait{};
  EXPECT_TRUE(limit.allowed(10s, wait)) << "nothing marked yet";
  EXPECT_EQ(wait, 0ns);
  limit.mark(10s);
  EXPECT_FALSE(limit.allowed(10s + 100ms, wait));
  EXPECT_EQ(wait, 400ms);
  EXPECT_FALSE(limit.allowed(10s + 499ms, wait));
  EXPECT_EQ(wait, 1ms);
  EXPECT_TRUE(limit.allowed(10s + 500ms, wait)) << "refusals pushed the next slot back";
  limit.mark(10s + 700ms);
  EXPECT_FALSE(limit.allowed(11s, wait));
  EXPECT_TRUE(limit.allowed(11s + 200ms, wait));
}

}  // namespace
}  // namespace weedspray::daemon
