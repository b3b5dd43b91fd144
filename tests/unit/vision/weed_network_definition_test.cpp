// SPDX-License-Identifier: Apache-2.0
// WeedNetwork against OpenCV's own definitions, with tests/data/tiny-3class.onnx on random
// frames: its input blob against cv::dnn::blobFromImage, classes_at against the argmax of every
// score plane resized bilinearly (cv::resize INTER_LINEAR).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

#include "tiny_model.hpp"
#include "vision/weed_network.hpp"

namespace weedspray::vision {
namespace {

using test::tiny_model;

DnnModelSpec tiny_spec() {
  DnnModelSpec spec;
  spec.input_width = 64;
  spec.input_height = 64;
  spec.mean_rgb = {0, 0, 0};
  spec.scale = 1.0 / 255.0;
  spec.rgb = true;
  return spec;
}

// The definition: each score plane resized bilinearly to `size`, then the argmax per pixel.
cv::Mat reference_classes(const WeedNetwork& network, cv::Size size) {
  const cv::Mat& scores = network.scores();
  const int channels = scores.size[1];
  const int height = scores.size[2];
  const int width = scores.size[3];
  std::vector<cv::Mat> planes(static_cast<std::size_t>(channels));
  for (int c = 0; c < channels; ++c) {
    const cv::Mat plane(height, width, CV_32F,
                        const_cast<float*>(scores.ptr<float>()) + c * height * width);
    cv::resize(plane, planes[static_cast<std::size_t>(c)], size, 0, 0, cv::INTER_LINEAR);
  }
  const DnnModelSpec& spec = network.spec();
  cv::Mat classes(size, CV_8UC1);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      int best = 0;
      for (int c = 1; c < channels; ++c) {
        if (planes[static_cast<std::size_t>(c)].at<float>(y, x) >
            planes[static_cast<std::size_t>(best)].at<float>(y, x)) {
          best = c;
        }
      }
      classes.at<std::uint8_t>(y, x) = best == spec.crop_class   ? kClassCrop
                                       : best == spec.weed_class ? kClassWeed
                                                                 : kClassSoil;
    }
  }
  return classes;
}

// A frame of random colour blocks of `block` pixels: every network pixel borders others.
cv::Mat random_blocks(cv::Size size, int block, std::uint64_t seed) {
  cv::RNG random(seed);
  cv::Mat small((size.height + block - 1) / block, (size.width + block - 1) / block, CV_8UC3);
  random.fill(small, cv::RNG::UNIFORM, 0, 256);
  cv::Mat frame;
  cv::resize(small, frame, cv::Size(small.cols * block, small.rows * block), 0, 0,
             cv::INTER_NEAREST);
  return frame(cv::Rect(cv::Point(0, 0), size)).clone();
}

double share_differing(const cv::Mat& a, const cv::Mat& b) {
  return static_cast<double>(cv::countNonZero(a != b)) / static_cast<double>(a.total());
}

TEST(NetworkClassesAt, EnlargedClassesAreTheArgmaxOfBilinearScores) {
  WeedNetwork network(tiny_spec(), tiny_model());
  for (const int block : {1, 3, 8}) {
    network.segment(random_blocks(cv::Size(64, 64), block, 7 + block), false);
    for (const cv::Size size : {cv::Size(256, 160), cv::Size(301, 77), cv::Size(64, 200)}) {
      const cv::Mat reference = reference_classes(network, size);
      const cv::Mat& fine = network.classes_at(size);
      ASSERT_EQ(fine.size(), size);
      // Rounding may part a near tie between two classes; nothing else may differ.
      EXPECT_LT(share_differing(fine, reference), 0.001) << "block " << block << " " << size;
      // And it is not the network's grid enlarged.
      cv::Mat nearest;
      cv::resize(network.segment_result(), nearest, size, 0, 0, cv::INTER_NEAREST);
      EXPECT_GT(share_differing(nearest, reference), 0.01) << "block " << block << " " << size;
    }
  }
}

TEST(NetworkClassesAt, ShrunkClassesFollowTheSameDefinition) {
  WeedNetwork network(tiny_spec(), tiny_model());
  network.segment(random_blocks(cv::Size(64, 64), 2, 3), false);
  for (const cv::Size size : {cv::Size(40, 30), cv::Size(100, 20)}) {
    EXPECT_LT(share_differing(network.classes_at(size), reference_classes(network, size)), 0.001)
        << size;
  }
  EXPECT_EQ(network.classes_at(cv::Size(64, 64)).data, network.segment_result().data);
}

TEST(NetworkClassesAt, EachSegmentGetsItsOwnFineClasses) {
  WeedNetwork network(tiny_spec(), tiny_model());
  network.segment(random_blocks(cv::Size(64, 64), 4, 1), false);
  const cv::Mat first = network.classes_at(cv::Size(200, 200)).clone();
  network.segment(random_blocks(cv::Size(64, 64), 4, 2), false);
  const cv::Mat second = network.classes_at(cv::Size(200, 200));
  EXPECT_GT(share_differing(first, second), 0.1);
  EXPECT_LT(share_differing(second, reference_classes(network, cv::Size(200, 200))), 0.001);
}

TEST(NetworkInput, TheBlobIsBlobFromImagesForEitherChannelOrder) {
  const std::vector<std::uint8_t> bytes = tiny_model();
  cv::dnn::Net reference =
      cv::dnn::readNetFromONNX(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  const cv::Mat frame = random_blocks(cv::Size(64, 64), 1, 11);
  for (const bool model_rgb : {true, false}) {
    for (const bool frame_rgb : {true, false}) {
      DnnModelSpec spec = tiny_spec();
      spec.rgb = model_rgb;
      spec.mean_rgb = {100.0, 120.0, 90.0};
      spec.scale = 0.02;
      WeedNetwork network(spec, bytes);
      network.segment(frame, frame_rgb);
      const auto& m = spec.mean_rgb;
      const cv::Scalar mean =
          model_rgb ? cv::Scalar(m[0], m[1], m[2]) : cv::Scalar(m[2], m[1], m[0]);
      reference.setInput(cv::dnn::blobFromImage(frame, spec.scale, frame.size(), mean,
                                                frame_rgb != model_rgb, false));
      const cv::Mat expected = reference.forward();
      ASSERT_EQ(expected.total(), network.scores().total());
      EXPECT_LT(cv::norm(expected.reshape(1, 1), network.scores().reshape(1, 1), cv::NORM_INF),
                1e-4)
          << "model rgb " << model_rgb << ", frame rgb " << frame_rgb;
    }
  }
}

}  // namespace
}  // namespace weedspray::vision
