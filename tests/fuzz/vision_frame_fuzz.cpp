// SPDX-License-Identifier: Apache-2.0
// The vision pipeline on arbitrary frames: the first bytes choose the size, stride, grid,
// region of interest and weed source (vegetation, inter_row); the rest is pixel data. process()
// must never crash, read outside the view or produce densities outside [0, 1].
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "vision/pipeline.hpp"
#include "vision/weed_source.hpp"

namespace {

std::uint8_t take(const std::uint8_t*& data, std::size_t& size) {
  if (size == 0) return 0;
  --size;
  return *data++;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace weedspray::vision;
  PipelineConfig config = default_pipeline_config();
  const std::uint8_t a = take(data, size), b = take(data, size), c = take(data, size),
                     d = take(data, size), e = take(data, size);
  config.rows = 1 + a % 4;
  config.cols = 1 + b % 8;
  config.roi.left = (c % 50) / 100.0;
  config.roi.right = 0.5 + (c % 50) / 100.0 + 0.01;
  config.weed_source = (d & 1) ? WeedSource::kInterRow : WeedSource::kVegetation;
  config.threshold = static_cast<ThresholdMethod>(d / 2 % 7);
  Pipeline pipeline(config);
  const int width = 1 + e % 64;
  const int channels = 3;
  const std::size_t row_bytes = static_cast<std::size_t>(width) * channels;
  const int height = static_cast<int>(std::min<std::size_t>(size / row_bytes, 64));
  std::vector<std::uint8_t> pixels(data, data + static_cast<std::size_t>(height) * row_bytes);
  ImageView view;
  view.data = pixels.data();
  view.width = width;
  view.height = height;
  view.stride = row_bytes;
  for (int frame = 0; frame < 2; ++frame) {  // twice: the inter-row tracker's second frame
    const FrameResult& result = pipeline.process(view);
    for (double density : result.densities()) {
      if (!(density >= 0.0 && density <= 1.0)) std::abort();
    }
  }
  return 0;
}
