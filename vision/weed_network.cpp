// SPDX-License-Identifier: Apache-2.0
#include "vision/weed_network.hpp"

#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace weedspray::vision {
namespace {

[[noreturn]] void reject(const std::string& message) {
  throw std::invalid_argument("dnn model: " + message);
}

// Area averaging in two steps: by a whole factor of each side first (OpenCV's integer-ratio
// path), then the rest, on a frame that many times smaller. One INTER_AREA at a ratio that is
// no whole number takes OpenCV's slower general path over the whole frame. The factor divides
// the side exactly, so the frame's geometry is kept to the pixel. tools/train/evaluate.py
// resamples the same way.
int whole_factor(int from, int to) {
  for (int factor = from / to; factor > 1; --factor) {
    if (from % factor == 0) return factor;
  }
  return 1;
}

void area_shrink(const cv::Mat& image, cv::Size size, cv::Mat& whole, cv::Mat& out) {
  const cv::Size step(image.cols / whole_factor(image.cols, size.width),
                      image.rows / whole_factor(image.rows, size.height));
  if (step == image.size() || step == size) {
    cv::resize(image, out, size, 0, 0, cv::INTER_AREA);
    return;
  }
  cv::resize(image, whole, step, 0, 0, cv::INTER_AREA);
  cv::resize(whole, out, size, 0, 0, cv::INTER_AREA);
}

}  // namespace

WeedNetwork::WeedNetwork(const DnnModelSpec& spec, std::span<const std::uint8_t> onnx_bytes,
                         double frame_mm_per_px)
    : spec_(spec), frame_mm_per_px_(frame_mm_per_px) {
  if (auto problem = validate_dnn_spec(spec_)) reject(*problem);
  if (onnx_bytes.empty()) reject("no model bytes (the model file is missing or empty)");
  try {
    net_ = cv::dnn::readNetFromONNX(reinterpret_cast<const char*>(onnx_bytes.data()),
                                    onnx_bytes.size());
  } catch (const cv::Exception& error) {
    reject("not a loadable ONNX model (" + std::string(error.what()) + ")");
  }
  if (net_.empty()) reject("not a loadable ONNX model (OpenCV gave an empty network)");
  net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);

  // One forward pass at the spec's size, fed as is: the shapes are known only by running it.
  const cv::Mat probe(spec_.input_height, spec_.input_width, CV_8UC3, cv::Scalar::all(0));
  try {
    segment_at(probe, false, probe.size());
  } catch (const cv::Exception& error) {
    reject("forward pass at " + std::to_string(spec_.input_width) + "x" +
           std::to_string(spec_.input_height) + " failed (" + error.what() + ")");
  }
  const int classes = static_cast<int>(spec_.classes.size());
  if (scores_.dims != 4 || scores_.size[0] != 1 || scores_.size[1] != classes) {
    std::string shape;
    for (int d = 0; d < scores_.dims; ++d) {
      if (d > 0) shape += 'x';
      shape += std::to_string(scores_.size[d]);
    }
    reject("output shape " + shape + " is not 1 x " + std::to_string(classes) +
           " classes x H x W (classes lists " + std::to_string(classes) + " classes)");
  }
}

const cv::Mat& WeedNetwork::segment(const cv::Mat& image, bool image_is_rgb) {
  if (image.size() != image_size_) {
    const NetworkInputSize input =
        network_input_size(spec_, frame_mm_per_px_, image.cols, image.rows);
    image_size_ = image.size();
    input_size_ = cv::Size(input.width, input.height);
  }
  return segment_at(image, image_is_rgb, input_size_);
}

const cv::Mat& WeedNetwork::segment_at(const cv::Mat& image, bool image_is_rgb, cv::Size size) {
  // blobFromImage subtracts the mean given in the network's channel order (after the swap).
  const auto& m = spec_.mean_rgb;
  const cv::Scalar mean = spec_.rgb ? cv::Scalar(m[0], m[1], m[2]) : cv::Scalar(m[2], m[1], m[0]);
  const bool swap = image_is_rgb != spec_.rgb;
  // Area averaging, as tools/train feeds the network (the model's spec says so), so the
  // daemon reproduces the model's reported figures. blobFromImage's own resize is bilinear,
  // which aliases fine weeds away when shrinking a frame 3x.
  const bool shrinking = size.width <= image.cols && size.height <= image.rows;
  if (shrinking) {
    area_shrink(image, size, shrunk_by_whole_factor_, resized_);
  } else {
    cv::resize(image, resized_, size, 0, 0, cv::INTER_LINEAR);
  }
  cv::dnn::blobFromImage(resized_, blob_, spec_.scale, size, mean, swap, false);
  net_.setInput(blob_);
  scores_ = net_.forward();
  if (scores_.dims != 4 || scores_.size[0] != 1 ||
      scores_.size[1] != static_cast<int>(spec_.classes.size())) {
    return classes_;  // the constructor reports the shape
  }

  // Argmax at the network's resolution: zone densities need no more, and upsampling the
  // scores would cost more than the network's last layers.
  const int channels = scores_.size[1];
  const int height = scores_.size[2];
  const int width = scores_.size[3];
  const int plane = height * width;
  classes_.create(height, width, CV_8UC1);
  const float* scores = scores_.ptr<float>();
  std::uint8_t* out = classes_.ptr<std::uint8_t>();
  for (int i = 0; i < plane; ++i) {
    int best = 0;
    float best_score = scores[i];
    for (int c = 1; c < channels; ++c) {
      const float score = scores[c * plane + i];
      if (score > best_score) {
        best = c;
        best_score = score;
      }
    }
    out[i] = best == spec_.crop_class   ? kClassCrop
             : best == spec_.weed_class ? kClassWeed
                                        : kClassSoil;
  }
  return classes_;
}

}  // namespace weedspray::vision
