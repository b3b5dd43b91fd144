// A crop/weed/soil segmentation network run through OpenCV DNN (internal to vision/).
#pragma once

#include <cstdint>
#include <span>

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include "vision/weed_source.hpp"

namespace weedspray::vision {

class WeedNetwork {
 public:
  // Loads the ONNX model from its bytes and checks it with one forward pass: throws
  // std::invalid_argument when the bytes are not a loadable model, the spec is invalid, or
  // the output is not one score map per class of spec.classes.
  WeedNetwork(const DnnModelSpec& spec, std::span<const std::uint8_t> onnx_bytes);

  // Classes of `image` (CV_8UC3, B G R when !image_is_rgb) at the network's output
  // resolution: kClassSoil, kClassCrop or kClassWeed (argmax of the scores; classes that are
  // neither crop nor weed count as soil). Throws cv::Exception when the network fails.
  const cv::Mat& segment(const cv::Mat& image, bool image_is_rgb);

  // The last segment()'s classes.
  const cv::Mat& segment_result() const { return classes_; }
  const DnnModelSpec& spec() const { return spec_; }

 private:
  DnnModelSpec spec_;
  cv::dnn::Net net_;
  cv::Mat resized_;
  cv::Mat blob_;
  cv::Mat scores_;
  cv::Mat classes_;  // CV_8UC1
};

}  // namespace weedspray::vision
