// SPDX-License-Identifier: Apache-2.0
#include "io/linux/mjpeg_decoder.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <vector>

namespace weedspray::io::hw {
namespace {

// A JPEG of the given size: left half green, right half brown.
std::vector<std::uint8_t> jpeg_of(int width, int height) {
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(40, 200, 30));
  image(cv::Rect(width / 2, 0, width - width / 2, height)).setTo(cv::Scalar(30, 70, 120));
  std::vector<std::uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(".jpg", image, bytes, {cv::IMWRITE_JPEG_QUALITY, 95}));
  return bytes;
}

TEST(MjpegDecoder, DecodesAFrameOfTheNegotiatedSizeToBgr) {
  MjpegDecoder decoder(64, 48);
  const auto jpeg = jpeg_of(64, 48);
  ASSERT_EQ(decoder.decode(jpeg.data(), jpeg.size()), MjpegDecoder::Result::kOk) << decoder.error();
  ASSERT_EQ(decoder.stride(), 64u * 3);
  const std::uint8_t* left = decoder.bgr() + 24 * decoder.stride() + 8 * 3;
  const std::uint8_t* right = decoder.bgr() + 24 * decoder.stride() + 56 * 3;
  EXPECT_NEAR(left[0], 40, 6);
  EXPECT_NEAR(left[1], 200, 6);
  EXPECT_NEAR(left[2], 30, 6);
  EXPECT_NEAR(right[0], 30, 6);
  EXPECT_NEAR(right[1], 70, 6);
  EXPECT_NEAR(right[2], 120, 6);
}

TEST(MjpegDecoder, RefusesAnotherSizeAndSaysWhatTheHeaderClaimed) {
  MjpegDecoder decoder(64, 48);
  const auto jpeg = jpeg_of(80, 48);
  EXPECT_EQ(decoder.decode(jpeg.data(), jpeg.size()), MjpegDecoder::Result::kRefused);
  EXPECT_EQ(decoder.claimed_width(), 80);
  EXPECT_EQ(decoder.claimed_height(), 48);
  EXPECT_NE(std::string(decoder.error()), "");
}

// The libFuzzer find that replaced cv::imdecode: a header claiming ~1 gigapixel, for which
// OpenCV allocated 3 GB. Refused from the header alone.
TEST(MjpegDecoder, RefusesAHeaderClaimingAGigapixel) {
  const std::filesystem::path seed = std::filesystem::path(WEEDSPRAY_SOURCE_DIR) /
                                     "tests/fuzz/corpus/mjpeg_frame/header-claims-1-gigapixel.jpg";
  std::ifstream in(seed, std::ios::binary);
  ASSERT_TRUE(in) << seed;
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), {});
  MjpegDecoder decoder(48, 36);
  EXPECT_EQ(decoder.decode(bytes.data(), bytes.size()), MjpegDecoder::Result::kRefused);
  EXPECT_GT(static_cast<double>(decoder.claimed_width()) * decoder.claimed_height(), 1e8)
      << decoder.error();
}

TEST(MjpegDecoder, RefusesGarbageAndEmptyFramesAndStillDecodesAfterwards) {
  MjpegDecoder decoder(64, 48);
  const std::vector<std::uint8_t> garbage(500, 0x5a);
  EXPECT_EQ(decoder.decode(garbage.data(), garbage.size()), MjpegDecoder::Result::kRefused);
  EXPECT_EQ(decoder.claimed_width(), 0);
  EXPECT_EQ(decoder.decode(nullptr, 0), MjpegDecoder::Result::kRefused);
  const auto jpeg = jpeg_of(64, 48);
  EXPECT_EQ(decoder.decode(jpeg.data(), jpeg.size()), MjpegDecoder::Result::kOk);
}

TEST(MjpegDecoder, ATruncatedFrameIsDamagedOrRefusedNeverOk) {
  MjpegDecoder decoder(64, 48);
  const auto jpeg = jpeg_of(64, 48);
  const auto result = decoder.decode(jpeg.data(), jpeg.size() / 2);
  EXPECT_NE(result, MjpegDecoder::Result::kOk);
  EXPECT_NE(std::string(decoder.error()), "");
}

TEST(MjpegDecoder, RejectsANonsenseSize) {
  EXPECT_THROW(MjpegDecoder(0, 48), std::invalid_argument);
  EXPECT_THROW(MjpegDecoder(64, -1), std::invalid_argument);
}

}  // namespace
}  // namespace weedspray::io::hw
