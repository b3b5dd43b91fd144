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
};

// Every PNG/JPEG in images_dir with a mask of the same stem (PNG) in masks_dir, sorted by
// name. Throws std::runtime_error naming the folder or file that is missing or unreadable.
std::vector<LabelledImage> load_labelled_images(const std::filesystem::path& images_dir,
                                                const std::filesystem::path& masks_dir);

// Reads a colour image, throwing std::runtime_error naming the file when it cannot.
cv::Mat read_bgr_image(const std::filesystem::path& path);

}  // namespace weedspray::lab
