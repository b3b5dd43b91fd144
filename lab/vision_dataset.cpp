// SPDX-License-Identifier: Apache-2.0
#include "lab/vision_dataset.hpp"

#include <algorithm>
#include <fstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

namespace weedspray::lab {

cv::Mat read_bgr_image(const std::filesystem::path& path) {
  cv::Mat image = cv::imread(path.string(), cv::IMREAD_COLOR);
  if (image.empty()) throw std::runtime_error(path.string() + ": cannot read image");
  return image;
}

std::vector<std::string> read_stem_list(const std::filesystem::path& path) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error(path.string() + ": cannot read the list of image stems");
  std::vector<std::string> stems;
  for (std::string line; std::getline(file, line);) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    const auto last = line.find_last_not_of(" \t\r");
    stems.push_back(line.substr(first, last - first + 1));
  }
  if (stems.empty()) throw std::runtime_error(path.string() + ": no image stems");
  return stems;
}

std::vector<LabelledImage> load_labelled_images(const std::filesystem::path& images_dir,
                                                const std::filesystem::path& masks_dir,
                                                const std::vector<std::string>& stems) {
  for (const auto& dir : {images_dir, masks_dir}) {
    if (!std::filesystem::is_directory(dir)) {
      throw std::runtime_error(dir.string() + ": not a folder");
    }
  }
  std::vector<std::filesystem::path> paths;
  for (const auto& entry : std::filesystem::directory_iterator(images_dir)) {
    std::string extension = entry.path().extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
    if (extension == ".png" || extension == ".jpg" || extension == ".jpeg") {
      paths.push_back(entry.path());
    }
  }
  std::sort(paths.begin(), paths.end());
  if (!stems.empty()) {
    std::vector<std::filesystem::path> listed;
    for (const std::string& stem : stems) {
      const auto found = std::find_if(paths.begin(), paths.end(), [&](const auto& path) {
        return path.stem().string() == stem;
      });
      if (found == paths.end()) {
        throw std::runtime_error(images_dir.string() + ": no image for listed stem '" + stem + "'");
      }
      listed.push_back(*found);
    }
    paths = std::move(listed);
  }
  if (paths.empty()) throw std::runtime_error(images_dir.string() + ": no PNG/JPEG images");
  std::vector<LabelledImage> images;
  for (const auto& path : paths) {
    const std::filesystem::path mask_path = masks_dir / (path.stem().string() + ".png");
    if (!std::filesystem::exists(mask_path)) {
      throw std::runtime_error(mask_path.string() + ": mask missing for " + path.string());
    }
    LabelledImage image{path.stem().string(), read_bgr_image(path), {}, {}};
    cv::Mat mask = cv::imread(mask_path.string(), cv::IMREAD_GRAYSCALE);
    if (mask.empty()) throw std::runtime_error(mask_path.string() + ": cannot read mask");
    if (mask.size() != image.bgr.size()) {
      throw std::runtime_error(mask_path.string() + ": mask size differs from its image");
    }
    image.plant = mask != 0;
    image.mask = mask;
    images.push_back(std::move(image));
  }
  return images;
}

}  // namespace weedspray::lab
