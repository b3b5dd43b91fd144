// SPDX-License-Identifier: Apache-2.0
#include "vision/weed_network.hpp"

#include <algorithm>
#include <limits>
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
// the side exactly, so the frame's geometry is kept to the pixel. A rest that shrinks by less
// than half (800 -> 400 -> 384 rows at the default camera) is bilinear: its two taps already
// cover every source pixel, and OpenCV's general area path is several times slower there.
// tools/train/evaluate.py resamples the same way.
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
  const bool rest_under_half = step.width <= 2 * size.width && step.height <= 2 * size.height;
  cv::resize(whole, out, size, 0, 0, rest_under_half ? cv::INTER_LINEAR : cv::INTER_AREA);
}

// Taps from `to` output pixels onto `from` network pixels with pixel centres aligned (as
// cv::resize INTER_LINEAR), clamped at the edges.
void bilinear_taps(int from, int to, std::vector<BilinearTap>& taps) {
  taps.resize(static_cast<std::size_t>(to));
  const double ratio = static_cast<double>(from) / to;
  for (int i = 0; i < to; ++i) {
    const double source = std::clamp((i + 0.5) * ratio - 0.5, 0.0, from - 1.0);
    const int low = static_cast<int>(source);
    taps[static_cast<std::size_t>(i)] = {low, std::min(low + 1, from - 1),
                                         static_cast<float>(source - low)};
  }
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
  for (int channel = 0; channel < static_cast<int>(spec_.classes.size()); ++channel) {
    class_of_channel_.push_back(channel == spec_.crop_class   ? kClassCrop
                                : channel == spec_.weed_class ? kClassWeed
                                                              : kClassSoil);
  }
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
  // The mean in the network's channel order (after the swap).
  const auto& m = spec_.mean_rgb;
  const cv::Scalar mean = spec_.rgb ? cv::Scalar(m[0], m[1], m[2]) : cv::Scalar(m[2], m[1], m[0]);
  const bool swap = image_is_rgb != spec_.rgb;
  // Area averaging, as tools/train feeds the network (the model's spec says so), so the
  // daemon reproduces the model's reported figures (bilinear would alias fine weeds away when
  // shrinking a frame 3x).
  const bool shrinking = size.width <= image.cols && size.height <= image.rows;
  if (shrinking) {
    area_shrink(image, size, shrunk_by_whole_factor_, resized_);
  } else {
    cv::resize(image, resized_, size, 0, 0, cv::INTER_LINEAR);
  }
  // The blob as blobFromImage makes it (channels swapped, mean subtracted, scaled, planar) in
  // two passes where it takes several: a split, then one scaled conversion per channel into its
  // plane.
  const int blob_shape[] = {1, 3, size.height, size.width};
  blob_.create(4, blob_shape, CV_32F);
  cv::split(resized_, channels_.data());
  for (int n = 0; n < 3; ++n) {
    cv::Mat plane(size, CV_32F, blob_.ptr<float>(0, n));
    channels_[static_cast<std::size_t>(swap ? 2 - n : n)].convertTo(plane, CV_32F, spec_.scale,
                                                                    -mean[n] * spec_.scale);
  }
  net_.setInput(blob_);
  scores_ = net_.forward();
  fine_is_current_ = false;
  if (scores_.dims != 4 || scores_.size[0] != 1 ||
      scores_.size[1] != static_cast<int>(spec_.classes.size())) {
    return classes_;  // the constructor reports the shape
  }

  // Argmax at the network's resolution; classes_at() refines it to a frame's resolution.
  const int channels = scores_.size[1];
  const int height = scores_.size[2];
  const int width = scores_.size[3];
  const int plane = height * width;
  classes_.create(height, width, CV_8UC1);
  argmax_.create(height, width, CV_8UC1);
  const float* scores = scores_.ptr<float>();
  std::uint8_t* out = classes_.ptr<std::uint8_t>();
  std::uint8_t* channel_out = argmax_.ptr<std::uint8_t>();
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
    channel_out[i] = static_cast<std::uint8_t>(best);
    out[i] = class_of_channel_[static_cast<std::size_t>(best)];
  }
  return classes_;
}

// Hand-written rather than cv::resize of every score plane and an argmax over the frame: a
// pixel whose four neighbouring network pixels share one argmax keeps it (a convex mix of
// scores keeps a class that leads in each), so only pixels along class edges mix scores. At
// 1280 x 800 that costs a fraction of three float planes resized and compared.
const cv::Mat& WeedNetwork::classes_at(cv::Size size) {
  if (argmax_.empty() || size == argmax_.size()) return classes_;
  if (fine_is_current_ && fine_.size() == size) return fine_;
  fine_is_current_ = true;
  const cv::Size from = argmax_.size();
  if (from != taps_from_ || size != taps_to_) {
    bilinear_taps(from.width, size.width, column_taps_);
    bilinear_taps(from.height, size.height, row_taps_);
    column_runs_.clear();
    for (int x = 0; x < size.width; ++x) {
      const BilinearTap& tap = column_taps_[static_cast<std::size_t>(x)];
      if (column_runs_.empty() || column_runs_.back().low != tap.low) {
        column_runs_.push_back({tap.low, tap.high, x, x});
      }
      column_runs_.back().end = x + 1;
    }
    taps_from_ = from;
    taps_to_ = size;
    run_offset_.resize(static_cast<std::size_t>(scores_.size[1]));
    run_slope_.resize(run_offset_.size());
    mixed_runs_.reserve(column_runs_.size());
  }
  // Where the four neighbours agree, the nearest of them is as good as any: OpenCV's
  // nearest-neighbour resize fills those pixels; only the others are mixed below. A nearest
  // pixel is one of the four only when enlarging.
  const bool enlarging = size.width >= from.width && size.height >= from.height;
  if (enlarging) {
    cv::resize(classes_, fine_, size, 0, 0, cv::INTER_NEAREST);
  } else {
    fine_.create(size, CV_8UC1);
  }
  const int channels = scores_.size[1];
  const std::size_t plane = static_cast<std::size_t>(from.width) * from.height;
  const float* scores = scores_.ptr<float>();
  int pair_low = -1;
  int pair_high = -1;
  for (int y = 0; y < size.height; ++y) {
    const BilinearTap row = row_taps_[static_cast<std::size_t>(y)];
    const std::size_t upper_row = static_cast<std::size_t>(row.low) * from.width;
    const std::size_t lower_row = static_cast<std::size_t>(row.high) * from.width;
    if (row.low != pair_low || row.high != pair_high) {  // the runs to mix, once per row pair
      pair_low = row.low;
      pair_high = row.high;
      const std::uint8_t* upper = argmax_.ptr<std::uint8_t>(row.low);
      const std::uint8_t* lower = argmax_.ptr<std::uint8_t>(row.high);
      mixed_runs_.clear();
      for (const ColumnRun& run : column_runs_) {
        const std::uint8_t corner = upper[run.low];
        if (!enlarging || corner != upper[run.high] || corner != lower[run.low] ||
            corner != lower[run.high]) {
          mixed_runs_.push_back(&run);
        }
      }
    }
    std::uint8_t* out = fine_.ptr<std::uint8_t>(y);
    for (const ColumnRun* mixed : mixed_runs_) {
      const ColumnRun& run = *mixed;
      // Along a run only the column weight changes: each channel's score is offset + slope x
      // weight, both mixed from the four neighbours once per run.
      for (int c = 0; c < channels; ++c) {
        const float* s = scores + c * plane;
        const float low =
            s[upper_row + run.low] + row.weight * (s[lower_row + run.low] - s[upper_row + run.low]);
        const float high = s[upper_row + run.high] +
                           row.weight * (s[lower_row + run.high] - s[upper_row + run.high]);
        run_offset_[static_cast<std::size_t>(c)] = low;
        run_slope_[static_cast<std::size_t>(c)] = high - low;
      }
      for (int x = run.begin; x < run.end; ++x) {
        const float weight = column_taps_[static_cast<std::size_t>(x)].weight;
        int best = 0;
        float best_score = run_offset_[0] + weight * run_slope_[0];
        for (int c = 1; c < channels; ++c) {
          const float score = run_offset_[static_cast<std::size_t>(c)] +
                              weight * run_slope_[static_cast<std::size_t>(c)];
          if (score > best_score) {
            best = c;
            best_score = score;
          }
        }
        out[x] = class_of_channel_[static_cast<std::size_t>(best)];
      }
    }
  }
  return fine_;
}

}  // namespace weedspray::vision
