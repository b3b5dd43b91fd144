// SPDX-License-Identifier: Apache-2.0
// A crop/weed/soil segmentation network run through OpenCV DNN (internal to vision/).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include "vision/weed_source.hpp"

namespace weedspray::vision {

// One output coordinate's two neighbouring network pixels and the weight of the second.
struct BilinearTap {
  int low = 0;
  int high = 0;
  float weight = 0.0f;
};

class WeedNetwork {
 public:
  // Loads the ONNX model from its bytes and checks it with one forward pass: throws
  // std::invalid_argument when the bytes are not a loadable model, the spec is invalid, or
  // the output is not one score map per class of spec.classes.
  // frame_mm_per_px: the ground size of one pixel of the images segment() gets (0 = unknown;
  // see network_input_size).
  WeedNetwork(const DnnModelSpec& spec, std::span<const std::uint8_t> onnx_bytes,
              double frame_mm_per_px = 0.0);

  // Classes of `image` (CV_8UC3, B G R when !image_is_rgb), resampled to the model's ground
  // scale (network_input_size), at the network's output resolution: kClassSoil, kClassCrop or
  // kClassWeed (argmax of the scores; classes that are neither crop nor weed count as soil). Throws
  // cv::Exception when the network fails.
  const cv::Mat& segment(const cv::Mat& image, bool image_is_rgb);

  // The last segment()'s classes.
  const cv::Mat& segment_result() const { return classes_; }

  // The last segment()'s classes at `size` (the image's own, typically): the argmax of the
  // scores interpolated bilinearly (pixel centres aligned, as cv::resize INTER_LINEAR), which
  // draws plant edges finer than the network's grid. Sized once per size: a steady stream
  // allocates nothing.
  const cv::Mat& classes_at(cv::Size size);
  const DnnModelSpec& spec() const { return spec_; }
  // The last segment()'s scores (1 x classes x H x W) and network input size.
  const cv::Mat& scores() const { return scores_; }
  cv::Size input_size() const { return input_size_; }

 private:
  // segment() at a given network input size.
  const cv::Mat& segment_at(const cv::Mat& image, bool image_is_rgb, cv::Size size);

  DnnModelSpec spec_;
  double frame_mm_per_px_ = 0.0;
  cv::Size image_size_;  // the last image's size and the network input it maps to
  cv::Size input_size_;
  cv::dnn::Net net_;
  cv::Mat shrunk_by_whole_factor_;  // area_shrink's first step
  cv::Mat resized_;
  std::array<cv::Mat, 3> channels_;  // the resized image's planes
  cv::Mat blob_;
  cv::Mat scores_;
  cv::Mat classes_;               // CV_8UC1
  cv::Mat argmax_;                // CV_8UC1: the score channel each network pixel's argmax picked
  cv::Mat fine_;                  // classes_at()'s classes
  bool fine_is_current_ = false;  // fine_ holds the last segment()'s classes
  std::vector<std::uint8_t> class_of_channel_;  // kClass* of each score channel
  std::vector<BilinearTap> column_taps_, row_taps_;
  struct ColumnRun {  // output columns [begin, end) that share their network pixels
    int low, high, begin, end;
  };
  std::vector<ColumnRun> column_runs_;
  std::vector<const ColumnRun*> mixed_runs_;   // one row pair's runs whose neighbours differ
  std::vector<float> run_offset_, run_slope_;  // per score channel, one run's mix
  cv::Size taps_from_, taps_to_;  // the network output and classes_at() sizes the taps map
};

}  // namespace weedspray::vision
