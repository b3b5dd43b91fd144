// SPDX-License-Identifier: Apache-2.0
// Reads a field image file (PNG through libpng, JPEG through libjpeg-turbo) into an 8-bit BGR
// matrix, the order the vision library takes. The simulated camera's only decoder: it keeps
// OpenCV's imgcodecs, and the ~140 libraries it maps (GDAL among them), out of weedsprayd.
#pragma once

#include <filesystem>
#include <string>

#include <opencv2/core/mat.hpp>

namespace weedspray::io::sim {

// The image, or an empty matrix with `error` saying why (the file, and what failed).
cv::Mat read_bgr_image(const std::filesystem::path& path, std::string& error);

// Whether read_bgr_image takes this file name's extension (*.png, *.jpg, *.jpeg).
bool is_readable_image(const std::filesystem::path& path);

}  // namespace weedspray::io::sim
