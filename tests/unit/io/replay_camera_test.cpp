// SPDX-License-Identifier: Apache-2.0
#include "io/sim/replay_camera.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "io/sim/ground_mosaic.hpp"
#include "io/sim/image_file.hpp"
#include "io/sim/manual_clock.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace weedspray::io::sim {
namespace {

using namespace std::chrono_literals;

std::string images_dir() {
  const char* data = std::getenv("WEEDSPRAY_DATA_DIR");
  if (data == nullptr) {
    ADD_FAILURE() << "WEEDSPRAY_DATA_DIR is not set (ctest sets it)";
    return {};
  }
  return std::string(data) + "/ews-train/images";
}

TEST(ReplayCamera, FixedRatePacingAndTimestampsFromTheClock) {
  ManualClock clock(1s);
  ReplayCameraConfig config;
  config.source = images_dir();
  config.fps = 10.0;
  ReplayCamera camera(config, clock);
  ASSERT_TRUE(camera.start()) << camera.last_error();
  EXPECT_GT(camera.image_count(), 100U);
  Frame f;
  for (int i = 0; i < 3; ++i) {
    ASSERT_EQ(camera.next_frame(f, 1s), FrameStatus::kOk) << camera.last_error();
    EXPECT_EQ(f.timestamp, 1s + i * 100ms);
    EXPECT_EQ(f.sequence, static_cast<std::uint64_t>(i));
    EXPECT_GT(f.view.width, 0);
    EXPECT_GT(f.view.height, 0);
    EXPECT_GE(f.view.stride, static_cast<std::size_t>(f.view.width) * 3);
    EXPECT_EQ(f.view.format, vision::PixelFormat::kBgr24);
    ASSERT_NE(f.view.data, nullptr);
  }
  EXPECT_EQ(camera.counters().frames, 3U);
}

TEST(ReplayCamera, PacedByGroundSpeedAndFootprint) {
  ManualClock clock;
  std::atomic<double> speed{2.0};
  ReplayCameraConfig config;
  config.source = images_dir();
  config.footprint_length_m = 1.0;
  config.ground_speed_m_per_s = [&] { return speed.load(); };
  ReplayCamera camera(config, clock);
  ASSERT_TRUE(camera.start()) << camera.last_error();
  Frame f;
  ASSERT_EQ(camera.next_frame(f, 1s), FrameStatus::kOk);
  EXPECT_EQ(f.timestamp, 0s);
  ASSERT_EQ(camera.next_frame(f, 1s), FrameStatus::kOk);
  EXPECT_EQ(f.timestamp, 500ms) << "1 m footprint at 2 m/s";
  speed = 0.0;
  EXPECT_EQ(camera.next_frame(f, 200ms), FrameStatus::kTimeout) << "standing still";
  EXPECT_EQ(camera.counters().timeouts, 1U);
}

TEST(ReplayCamera, SingleImageWithoutLoopEnds) {
  ManualClock clock;
  ReplayCameraConfig config;
  const auto first = *std::filesystem::directory_iterator(images_dir());
  config.source = first.path().string();
  config.loop = false;
  ReplayCamera camera(config, clock);
  ASSERT_TRUE(camera.start()) << camera.last_error();
  Frame f;
  EXPECT_EQ(camera.next_frame(f, 1s), FrameStatus::kOk);
  EXPECT_EQ(camera.next_frame(f, 1s), FrameStatus::kEnd);
}

// A video is refused at start with a message that says what to do instead (the daemon reads
// no video: OpenCV's videoio would map some 240 libraries into it).
TEST(ReplayCamera, AVideoFileIsRefusedSayingHowToExtractItsFrames) {
  char tmpl[] = "/tmp/weedspray-replay-XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  const std::string path = std::string(tmpl) + "/run.avi";
  std::ofstream(path) << "not really a video";
  ManualClock clock;
  ReplayCameraConfig config;
  config.source = path;
  ReplayCamera camera(config, clock);
  EXPECT_FALSE(camera.start());
  EXPECT_NE(camera.last_error().find("extract its frames first"), std::string::npos)
      << camera.last_error();
  std::filesystem::remove_all(tmpl);
}

// PNG and JPEG files decode to the BGR pixels OpenCV's own codecs wrote (JPEG within its loss);
// a file that is not what its name says fails with the file named.
TEST(ImageFile, ReadsPngAndJpegAsBgrAndNamesAFileItCannotRead) {
  char tmpl[] = "/tmp/weedspray-image-XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  const std::filesystem::path dir(tmpl);
  cv::Mat picture(48, 64, CV_8UC3);
  for (int y = 0; y < picture.rows; ++y)
    for (int x = 0; x < picture.cols; ++x)
      picture.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<std::uint8_t>(x * 4), 200, static_cast<std::uint8_t>(y * 5));
  ASSERT_TRUE(cv::imwrite((dir / "a.png").string(), picture));
  ASSERT_TRUE(cv::imwrite((dir / "b.JPG").string(), picture, {cv::IMWRITE_JPEG_QUALITY, 95}));
  std::string error;
  const cv::Mat png = read_bgr_image(dir / "a.png", error);
  ASSERT_FALSE(png.empty()) << error;
  EXPECT_EQ(cv::norm(png, picture, cv::NORM_INF), 0.0);
  const cv::Mat jpeg = read_bgr_image(dir / "b.JPG", error);
  ASSERT_FALSE(jpeg.empty()) << error;
  ASSERT_EQ(jpeg.size(), picture.size());
  EXPECT_LT(cv::norm(jpeg, picture, cv::NORM_L1) / static_cast<double>(picture.total() * 3), 3.0);
  std::ofstream(dir / "c.png") << "not a png";
  EXPECT_TRUE(read_bgr_image(dir / "c.png", error).empty());
  EXPECT_NE(error.find("c.png"), std::string::npos) << error;
  std::filesystem::remove_all(dir);
}

TEST(ReplayCamera, LaysImagesOfKnownScaleAtTheCamerasScale) {
  ManualClock clock(1s);
  ReplayCameraConfig config;
  config.source = images_dir();  // 350 x 350 px each
  config.fps = 10.0;
  config.source_mm_per_px = 0.5;
  config.frame_mm_per_px = 1.0;  // each image becomes 175 x 175 px
  config.frame_width = 400;
  config.frame_height = 200;
  ReplayCamera camera(config, clock);
  ASSERT_TRUE(camera.start()) << camera.last_error();
  Frame f;
  ASSERT_EQ(camera.next_frame(f, 1s), FrameStatus::kOk) << camera.last_error();
  EXPECT_EQ(f.view.width, 400);
  EXPECT_EQ(f.view.height, 200);
  // Three images across (175 + 175 + 50 px) in each of two rows (175 + 25 px).
  ASSERT_EQ(camera.next_frame(f, 1s), FrameStatus::kOk);
  config.frame_mm_per_px = 0.0;
  ReplayCamera without_scale(config, clock);
  EXPECT_FALSE(without_scale.start());
  EXPECT_NE(without_scale.last_error().find("frame_mm_per_px"), std::string::npos);
}

TEST(GroundMosaic, ImagesAreResampledAndLaidRowByRow) {
  int next = 0;
  // 40 x 20 photos of value 10, 20, 30 ... at 2 mm/px shown at 4 mm/px: 20 x 10 tiles.
  const GroundScale scale{2.0, 4.0, cv::Size(50, 15)};
  const cv::Mat ground = lay_ground(
      scale, [&] { return cv::Mat(20, 40, CV_8UC1, cv::Scalar(10 * ++next)); }, true);
  ASSERT_EQ(ground.size(), cv::Size(50, 15));
  EXPECT_EQ(ground.at<std::uint8_t>(0, 0), 10);
  EXPECT_EQ(ground.at<std::uint8_t>(0, 19), 10);
  EXPECT_EQ(ground.at<std::uint8_t>(0, 20), 20);
  EXPECT_EQ(ground.at<std::uint8_t>(0, 49), 30);  // the third tile, cut at the frame's edge
  EXPECT_EQ(ground.at<std::uint8_t>(10, 0), 40);  // the second row
  EXPECT_EQ(next, 6);
  EXPECT_THROW((void)lay_ground({0.0, 1.0, cv::Size(4, 4)}, [] { return cv::Mat(); }),
               std::invalid_argument);
}

TEST(ReplayCamera, MissingSourceIsAClearError) {
  ManualClock clock;
  ReplayCameraConfig config;
  config.source = "/nonexistent/field-run";
  ReplayCamera camera(config, clock);
  EXPECT_FALSE(camera.start());
  EXPECT_NE(camera.last_error().find("/nonexistent/field-run"), std::string::npos)
      << camera.last_error();
  Frame f;
  EXPECT_EQ(camera.next_frame(f, 10ms), FrameStatus::kError);
}

}  // namespace
}  // namespace weedspray::io::sim
