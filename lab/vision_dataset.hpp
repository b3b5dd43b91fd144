// SPDX-License-Identifier: Apache-2.0
// Loading the labelled field images (image folder + mask folder) for the vision commands.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace weedspray::lab {

struct LabelledImage {
  std::string name;  // file stem
  cv::Mat bgr;       // CV_8UC3
  cv::Mat plant;     // CV_8UC1, 255 = plant (any non-zero in the file)
  cv::Mat mask;      // CV_8UC1 as stored: class ids (0 soil, 1 crop, 2 weed) in class masks
};

// Every PNG/JPEG in images_dir with a mask of the same stem (PNG) in masks_dir, sorted by
// name; only the listed stems when `stems` is not empty (each must exist). Throws
// std::runtime_error naming the folder or file that is missing or unreadable.
std::vector<LabelledImage> load_labelled_images(const std::filesystem::path& images_dir,
                                                const std::filesystem::path& masks_dir,
                                                const std::vector<std::string>& stems = {});

// Image stems, one per line (blank lines ignored), e.g. tools/train/splits/peanut-val.txt.
std::vector<std::string> read_stem_list(const std::filesystem::path& path);

// Reads a colour image, throwing std::runtime_error naming the file when it cannot.
cv::Mat read_bgr_image(const std::filesystem::path& path);

}  // namespace weedspray::lab
