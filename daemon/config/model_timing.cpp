// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/model_timing.hpp"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <opencv2/core.hpp>
#include <sstream>

#include "daemon/config/vision_config.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::daemon {
namespace {

// OpenCV's thread count for one scope: the daemon's vision worker runs on one thread.
class SingleThreadedOpenCv {
 public:
  SingleThreadedOpenCv() : saved_(cv::getNumThreads()) { cv::setNumThreads(1); }
  ~SingleThreadedOpenCv() { cv::setNumThreads(saved_); }
  SingleThreadedOpenCv(const SingleThreadedOpenCv&) = delete;
  SingleThreadedOpenCv& operator=(const SingleThreadedOpenCv&) = delete;

 private:
  int saved_;
};

}  // namespace

std::vector<std::string> time_model_use(const Config& config, int frames) {
  std::vector<std::string> lines;
  if (!config.model) return lines;
  const SingleThreadedOpenCv one_thread;
  for (std::size_t i = 0; i < config.cameras.size(); ++i) {
    const CameraSection& camera = config.cameras[i];
    vision::Pipeline pipeline(pipeline_config(config, camera), config.model->onnx);
    // A plain soil-coloured frame: the network's cost does not depend on what it sees.
    std::vector<std::uint8_t> pixels(static_cast<std::size_t>(camera.width) * camera.height * 3);
    for (std::size_t p = 0; p < pixels.size(); p += 3) {
      pixels[p] = 70;
      pixels[p + 1] = 100;
      pixels[p + 2] = 130;
    }
    const vision::ImageView frame{pixels.data(), camera.width, camera.height,
                                  static_cast<std::size_t>(camera.width) * 3,
                                  vision::PixelFormat::kBgr24};
    std::vector<double> milliseconds;
    for (int n = 0; n <= std::max(1, frames); ++n) {
      const auto start = std::chrono::steady_clock::now();
      (void)pipeline.process(frame);
      const auto stop = std::chrono::steady_clock::now();
      if (!pipeline.last_frame_ok()) {
        throw VisionKeyError("vision.model", config.model->path.string() + ": fails on camera[" +
                                                 std::to_string(i) +
                                                 "]'s frames: " + pipeline.last_error());
      }
      if (n > 0)
        milliseconds.push_back(std::chrono::duration<double, std::milli>(stop - start).count());
    }
    std::sort(milliseconds.begin(), milliseconds.end());
    std::ostringstream line;
    line.precision(3);
    line << "camera[" << i << "]: " << config.vision.weed_source << " on " << camera.width << "x"
         << camera.height << " frames: " << milliseconds[milliseconds.size() / 2]
         << " ms per frame on this machine (one thread)";
    lines.push_back(line.str());
  }
  return lines;
}

}  // namespace weedspray::daemon
