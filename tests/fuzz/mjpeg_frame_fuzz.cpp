// SPDX-License-Identifier: Apache-2.0
// An MJPEG frame as the V4L2 camera decodes it (io::hw::MjpegDecoder, libjpeg-turbo) followed
// by the vision pipeline on whatever decodes: a malformed frame must be refused without
// crashing or allocating what its header claims. It replaced a target on cv::imdecode, which
// found that OpenCV allocates 3 GB for a JPEG header claiming a gigapixel
// (corpus/mjpeg_frame/header-claims-1-gigapixel.jpg). The seeds are 48x36 frames.
#include <cstddef>
#include <cstdint>

#include "io/linux/mjpeg_decoder.hpp"
#include "vision/pipeline.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static weedspray::io::hw::MjpegDecoder decoder(48, 36);
  static weedspray::vision::Pipeline pipeline(weedspray::vision::default_pipeline_config());
  if (decoder.decode(data, size) == weedspray::io::hw::MjpegDecoder::Result::kRefused) return 0;
  weedspray::vision::ImageView view;
  view.data = decoder.bgr();
  view.width = decoder.width();
  view.height = decoder.height();
  view.stride = decoder.stride();
  (void)pipeline.process(view);
  return 0;
}
