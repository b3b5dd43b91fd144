#include "lab/experiment_field.hpp"

#include <algorithm>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

#include "vision/pipeline.hpp"

namespace weedspray::lab {

std::vector<std::array<double, 4>> field_zone_densities(const std::string& images_dir) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(images_dir))
    throw std::runtime_error("field images directory not found: " + images_dir);
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(images_dir))
    if (entry.path().extension() == ".png" || entry.path().extension() == ".jpg")
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error("no .png/.jpg images in " + images_dir);

  vision::PipelineConfig config = vision::default_pipeline_config();
  config.rows = 2;
  config.cols = 4;
  vision::Pipeline pipeline(config);
  std::vector<std::array<double, 4>> zones;
  for (const auto& file : files) {
    const cv::Mat bgr = cv::imread(file.string(), cv::IMREAD_COLOR);
    if (bgr.empty()) throw std::runtime_error("cannot read image: " + file.string());
    const vision::ImageView view{bgr.data, bgr.cols, bgr.rows, bgr.step[0],
                                 vision::PixelFormat::kBgr24};
    const vision::FrameResult& r = pipeline.process(view);
    // Row 0 is the top of the frame: the ground farther ahead, reached later. Travel order is
    // therefore the near (bottom) row first.
    for (int row = r.rows - 1; row >= 0; --row) {
      std::array<double, 4> zone{};
      for (int col = 0; col < 4; ++col) zone[static_cast<std::size_t>(col)] = r.density(row, col);
      zones.push_back(zone);
    }
  }
  return zones;
}

}  // namespace weedspray::lab
