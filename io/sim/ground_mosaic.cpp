// SPDX-License-Identifier: Apache-2.0
#include "io/sim/ground_mosaic.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace weedspray::io::sim {

cv::Mat lay_ground(const GroundScale& scale, const std::function<cv::Mat()>& next_photo,
                   bool is_mask) {
  if (!(scale.source_mm_per_px > 0.0) || !(scale.frame_mm_per_px > 0.0) || scale.frame.width < 1 ||
      scale.frame.height < 1) {
    throw std::invalid_argument(
        "lay_ground: source and frame mm per pixel must be > 0 and the "
        "frame not empty");
  }
  const double factor = scale.source_mm_per_px / scale.frame_mm_per_px;
  const int interpolation = is_mask        ? cv::INTER_NEAREST
                            : factor < 1.0 ? cv::INTER_AREA
                                           : cv::INTER_LINEAR;
  cv::Mat frame;
  int y = 0;
  while (y < scale.frame.height) {
    int x = 0;
    int row_height = 0;
    while (x < scale.frame.width) {
      const cv::Mat photo = next_photo();
      if (photo.empty()) throw std::invalid_argument("lay_ground: an empty photo");
      if (frame.empty()) frame = cv::Mat::zeros(scale.frame, photo.type());
      cv::Mat resampled;
      const cv::Size size(std::max(1, static_cast<int>(std::lround(photo.cols * factor))),
                          std::max(1, static_cast<int>(std::lround(photo.rows * factor))));
      cv::resize(photo, resampled, size, 0, 0, interpolation);
      const int w = std::min(resampled.cols, scale.frame.width - x);
      const int h = std::min(resampled.rows, scale.frame.height - y);
      if (w < 1 || h < 1) break;
      resampled(cv::Rect(0, 0, w, h)).copyTo(frame(cv::Rect(x, y, w, h)));
      x += w;
      row_height = std::max(row_height, h);
    }
    if (row_height == 0) break;
    y += row_height;
  }
  return frame;
}

}  // namespace weedspray::io::sim
