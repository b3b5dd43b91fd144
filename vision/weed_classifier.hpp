// SPDX-License-Identifier: Apache-2.0
// Weed and crop densities per zone for the inter_row, dnn, hybrid, plants and dnn_vegetation weed
// sources, from the frame, its vegetation index image and threshold (internal to vision/; Pipeline
// owns one).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "vision/image_view.hpp"
#include "vision/pipeline.hpp"
#include "vision/plant_classes.hpp"
#include "vision/weed_inter_row.hpp"

namespace weedspray::vision {

class WeedNetwork;

class WeedClassifier {
 public:
  // Throws std::invalid_argument when the source needs a model and the bytes do not give a
  // usable one (see Pipeline's constructor).
  WeedClassifier(const PipelineConfig& config, std::span<const std::uint8_t> model_onnx_bytes);
  ~WeedClassifier();
  WeedClassifier(const WeedClassifier&) = delete;
  WeedClassifier& operator=(const WeedClassifier&) = delete;

  // Fills result.zone_density (weed) and result.crop_density. `index` is the region's index
  // image (region.width bytes per row); vegetation is index > level. Returns false with
  // `error` set when the network fails; never throws.
  bool classify(const ImageView& frame, const PixelRect& region, const std::uint8_t* index,
                std::uint8_t level, FrameResult& result, std::string& error);

  void reset_tracking() { tracker_.reset(); }
  const CropRowTracker& tracker() const { return tracker_; }

  // The last classified frame's class map (see Pipeline::class_map), written into `out`
  // (at least region width x height bytes, packed rows).
  ImageView class_map(const std::uint8_t* index, std::uint8_t level, std::span<std::uint8_t> out);
  // The network input the last frame became (x = y = 0; empty for sources without a network).
  PixelRect network_input() const;

 private:
  // index > level over the region, into the masks' vegetation buffer.
  const cv::Mat& vegetation_mask(const std::uint8_t* index, std::uint8_t level);
  void classify_inter_row(const std::uint8_t* index, std::uint8_t level, FrameResult& result);
  // The network on the frame's region; network_classes() then gives its classes at the
  // region's resolution.
  void run_network(const ImageView& frame);
  const cv::Mat& network_classes();
  void classify_hybrid(const std::uint8_t* index, std::uint8_t level, FrameResult& result);
  void classify_plants(const std::uint8_t* index, std::uint8_t level, FrameResult& result);
  void classify_dnn_vegetation(const std::uint8_t* index, std::uint8_t level, FrameResult& result);

  PipelineConfig config_;
  PixelRect region_{};
  CropRowTracker tracker_;
  std::vector<std::uint32_t> zone_row_columns_;  // inter_row: per zone row, per column
  std::vector<std::uint8_t> in_band_;            // inter_row: column lies in a crop-row band
  std::unique_ptr<WeedNetwork> network_;         // the sources that need a model
  PlantClasses plants_;                          // plants; its join serves dnn_vegetation too
  struct Masks;
  std::unique_ptr<Masks> masks_;  // OpenCV buffers (hybrid, plants, dnn_vegetation masks)
};

}  // namespace weedspray::vision
