// Image decoding as the replay camera does it (OpenCV's imdecode: PNG, JPEG, ...) followed by
// the vision pipeline on whatever decodes: malformed files must be rejected, not crash.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "vision/pipeline.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> bytes(data, data + size);
  cv::Mat image;
  try {
    image = cv::imdecode(bytes, cv::IMREAD_COLOR);
  } catch (const cv::Exception&) {
    return 0;  // OpenCV's own refusal
  }
  if (image.empty() || image.total() > 4096 * 4096) return 0;
  static weedspray::vision::Pipeline pipeline(weedspray::vision::default_pipeline_config());
  weedspray::vision::ImageView view;
  view.data = image.data;
  view.width = image.cols;
  view.height = image.rows;
  view.stride = image.step;
  (void)pipeline.process(view);
  return 0;
}
