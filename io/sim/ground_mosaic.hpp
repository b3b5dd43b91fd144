// SPDX-License-Identifier: Apache-2.0
// The ground as a camera of another scale would see it: photos of known ground resolution
// resampled to the camera's and laid edge to edge, row by row, to fill its frame.
#pragma once

#include <functional>
#include <opencv2/core.hpp>

namespace weedspray::io::sim {

struct GroundScale {
  double source_mm_per_px = 0.0;  // ground size of one pixel of the photos
  double frame_mm_per_px = 0.0;   // ground size of one pixel of the camera's frame
  cv::Size frame{};               // the camera's frame size
};

// Photos of the scale's source resolution, each resampled by source / frame, laid in rows to
// fill `scale.frame`: next_photo() is asked for each place in turn (left to right, top to
// bottom) and returns a photo (CV_8UC3, or CV_8UC1 masks). Photos are shrunk with area
// averaging (INTER_AREA), enlarged bilinearly; masks (nearest) keep their ids. Throws
// std::invalid_argument for a scale <= 0 or an empty frame.
cv::Mat lay_ground(const GroundScale& scale, const std::function<cv::Mat()>& next_photo,
                   bool is_mask = false);

}  // namespace weedspray::io::sim
