// The vision pipeline the daemon runs on every frame:
//   frame -> vegetation index (+ histogram, one pass) -> threshold -> zone densities
// Pure: no threads, no I/O. After the first frame of a given size, process() allocates
// nothing (buffers are reused).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "vision/histogram.hpp"
#include "vision/image_view.hpp"
#include "vision/threshold.hpp"
#include "vision/vegetation_index.hpp"
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
};

// The project's default: the index and threshold the daemon uses unless configured otherwise
// (chosen by measured IoU on data/ews-train; see weedspray-lab vision-eval). CIVE with Otsu
// where the histogram is bimodal and CIVE's fixed level where it is not; the UGV paper's
// choice is index = kExgNormalized, threshold = kFit.
PipelineConfig default_pipeline_config();

// Throws std::invalid_argument naming the offending field (start-up only).
void validate(const PipelineConfig& config);

struct FrameResult {
  int threshold = 0;               // vegetation is index value > threshold
  bool bimodal = false;            // the histogram had two classes
  double vegetation_fraction = 0;  // over the region of interest
  int rows = 0;
  int cols = 0;
  std::array<double, kMaxZones> zone_density{};  // row-major, rows * cols used
  std::array<DensityLevel, kMaxZones> zone_level{};
  InterRowMap inter_row{};  // filled when PipelineConfig::inter_row_map
  std::span<const double> densities() const {
    return {zone_density.data(), static_cast<std::size_t>(rows * cols)};
  }
  double density(int row, int col) const { return zone_density[row * cols + col]; }
};

class Pipeline {
 public:
  // Throws std::invalid_argument on a bad config (see validate).
  explicit Pipeline(const PipelineConfig& config);

  // Processes one frame. The result stays valid until the next call. An empty or malformed
  // view (null data, size < 2x2, stride too small) gives an all-zero result with
  // valid = false in last_frame_ok().
  const FrameResult& process(const ImageView& frame);

  bool last_frame_ok() const { return last_frame_ok_; }
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
};

}  // namespace weedspray::vision
