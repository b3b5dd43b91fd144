// SPDX-License-Identifier: Apache-2.0
// The vision pipeline the daemon runs on every frame:
//   frame -> vegetation index (+ histogram, one pass) -> threshold -> zone densities
// Pure: no threads, no I/O. After the first frame of a given size, process() allocates
// nothing (buffers are reused).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "vision/histogram.hpp"
#include "vision/image_view.hpp"
#include "vision/threshold.hpp"
#include "vision/vegetation_index.hpp"
#include "vision/weed_inter_row.hpp"
#include "vision/weed_source.hpp"
#include "vision/zones.hpp"

namespace weedspray::vision {

inline constexpr int kMaxZones = 64;  // rows * cols

// Defaults are the project's pipeline (default_pipeline_config()).
struct PipelineConfig {
  VegetationIndex index = VegetationIndex::kCive;
  ThresholdMethod threshold = ThresholdMethod::kOtsu;
  ThresholdParams threshold_params{};
  int rows = 1;  // zones along travel
  int cols = 4;  // zones across the boom: one per nozzle
  RegionOfInterest roi{};
  DensityLevelCuts level_cuts{};          // zone density -> level
  bool inter_row_map = false;             // also compute the 2018 lateral-histogram map
  double inter_row_fraction = 1.0 / 3.0;  // columns <= this fraction of the max are inter-row
  DensityLevelCuts inter_row_cuts{};      // p(n), share of the region's pixels -> level
  // What zone_density counts (see vision/weed_source.hpp).
  WeedSource weed_source = WeedSource::kVegetation;
  InterRowRule inter_row_rule{};  // kInterRow
  DnnModelSpec dnn{};             // kDnn, kHybrid, kPlants
  double frame_mm_per_px = 0.0;   // kDnn, kHybrid, kPlants: the camera's ground scale; 0 = unknown
  int crop_margin_px = 0;         // kHybrid: crop mask dilated by this many frame pixels
  int min_plant_px = 1;           // kPlants: smaller connected vegetation is not a plant
};

// The project's default: the index and threshold the daemon uses unless configured otherwise
// (chosen by measured IoU on data/ews-train; see weedspray-lab vision-eval). CIVE with Otsu
// where the histogram is bimodal; where it is not, Otsu's split unless it cuts the soil peak
// (UnimodalPolicy::kClearOfPeak, checked on data/peanut too); the UGV paper's choice is
// index = kExgNormalized, threshold = kFit.
PipelineConfig default_pipeline_config();

// Throws std::invalid_argument naming the offending field (start-up only).
void validate(const PipelineConfig& config);

struct FrameResult {
  int threshold = 0;               // vegetation is index value > threshold
  bool bimodal = false;            // the histogram had two classes
  double vegetation_fraction = 0;  // over the region of interest
  int rows = 0;
  int cols = 0;
  // WEED density per zone, what the rate law uses (for kVegetation: vegetation cover).
  std::array<double, kMaxZones> zone_density{};  // row-major, rows * cols used
  std::array<double, kMaxZones> crop_density{};  // share of each zone that is crop
  std::array<DensityLevel, kMaxZones> zone_level{};
  InterRowMap inter_row{};  // filled when PipelineConfig::inter_row_map
  std::span<const double> densities() const {
    return {zone_density.data(), static_cast<std::size_t>(rows * cols)};
  }
  double density(int row, int col) const { return zone_density[row * cols + col]; }
};

class WeedClassifier;

class Pipeline {
 public:
  // Throws std::invalid_argument on a bad config (see validate). dnn and hybrid need the
  // ONNX model's bytes (vision reads no files): missing or unloadable bytes, an output that
  // does not have dnn.classes.size() channels (one forward pass here) and bad class ids are
  // std::invalid_argument naming the problem.
  explicit Pipeline(const PipelineConfig& config,
                    std::span<const std::uint8_t> model_onnx_bytes = {});
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Processes one frame. The result stays valid until the next call. An empty or malformed
  // view (null data, size < 2x2, stride too small) gives an all-zero result with
  // valid = false in last_frame_ok(). A network that fails at run time gives the same, with
  // last_error() saying why; process() never throws.
  const FrameResult& process(const ImageView& frame);

  bool last_frame_ok() const { return last_frame_ok_; }
  const std::string& last_error() const { return last_error_; }
  // Forget the tracked crop rows (inter_row): the next frame is not a continuation.
  void reset_tracking();
  // The crop rows tracked so far (inter_row; empty for the other sources).
  std::span<const CropRow> crop_rows() const;
  // The last frame's class of each pixel (kClassSoil/kClassCrop/kClassWeed) over the region
  // of interest at the region's resolution, built on demand for overlays and evaluation.
  ImageView class_map();
  // The same written into `out` without allocating (the daemon's snapshot handoff): a view of
  // `out`, or an empty view when `out` is smaller than class_map_pixels().
  ImageView class_map_into(std::span<std::uint8_t> out);
  std::size_t class_map_pixels() const;
  // The network input the last frame was resampled to (x = y = 0; empty without a network).
  PixelRect network_input() const;
  const PipelineConfig& config() const { return config_; }
  // The last frame's index image over the region of interest and its pixel rectangle, for
  // overlays and evaluation (mask = index > threshold).
  ImageView index_image() const;
  PixelRect region() const { return region_; }
  const Histogram& histogram() const { return histogram_; }

 private:
  PipelineConfig config_;
  FrameResult result_{};
  Histogram histogram_{};
  std::vector<std::uint8_t> index_buffer_;
  std::vector<std::uint32_t> column_counts_;
  PixelRect region_{};
  bool last_frame_ok_ = false;
  std::string last_error_;
  std::unique_ptr<WeedClassifier> weeds_;   // null for kVegetation
  std::vector<std::uint8_t> class_buffer_;  // class_map() for kVegetation
};

}  // namespace weedspray::vision
