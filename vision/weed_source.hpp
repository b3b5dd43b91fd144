// SPDX-License-Identifier: Apache-2.0
// What the spray decision counts as weed: every green pixel (vegetation), vegetation between
// tracked crop rows (the 2018 paper's inter-row rule), a segmentation network's weed class
// (dnn), colour vegetation minus the network's crop mask (hybrid), colour-segmented plants
// each classified by the network's votes (plants), or the network's classes with their edges
// drawn by colour vegetation (dnn_vegetation).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace weedspray::vision {

enum class WeedSource : std::uint8_t {
  kVegetation,  // every vegetation pixel is weed (bare soil: fallow, pre-plant)
  kInterRow,    // vegetation outside the crop-row bands is weed
  kDnn,         // the network's weed class
  kHybrid,      // colour vegetation; crop where it lies within a margin of the network's crop
  kPlants,      // colour vegetation, each connected plant crop or weed by the network's votes
  // The network's class per pixel, but soil where colour finds no vegetation within about a
  // millimetre in the outer network pixel of what the network calls plant: the network decides
  // on a grid coarser than a leaf's edge, colour draws the edge.
  kDnnVegetation,
};

// Config names: "vegetation", "inter_row", "dnn", "hybrid", "plants", "dnn_vegetation".
std::optional<WeedSource> parse_weed_source(std::string_view name);
std::string_view to_string(WeedSource source);
std::span<const std::string_view> weed_source_names();
// dnn, hybrid, plants and dnn_vegetation need a model.
bool needs_model(WeedSource source);

// Class ids the pipeline reports per pixel (Pipeline::class_map), whatever the source.
inline constexpr std::uint8_t kClassSoil = 0;
inline constexpr std::uint8_t kClassCrop = 1;
inline constexpr std::uint8_t kClassWeed = 2;

// How a segmentation network is fed and read. The input is the region of interest resampled to
// the model's ground scale (network_input_size) or, where either scale is unknown, resized to
// input_width x input_height; each channel becomes (value - mean) * scale, in R, G, B order
// when rgb (else B, G, R). The output is one score map per class; the class of a pixel is the
// argmax over classes[...] at the network's output resolution.
struct DnnModelSpec {
  int input_width = 320;
  int input_height = 256;
  std::array<double, 3> mean_rgb = {123.675, 116.28, 103.53};  // ImageNet, on 0..255
  double scale = 1.0 / 58.0;
  bool rgb = true;
  std::vector<std::string> classes{"soil", "crop", "weed"};
  int soil_class = 0;
  int crop_class = 1;
  int weed_class = 2;
  // Ground size of one network-input pixel the model learnt at, in mm; 0 = not stated.
  double ground_mm_per_px = 0.0;
  int stride = 32;           // input sides must be multiples of this (the network's downsampling)
  int input_channels = 3;    // colour channels the network takes
  bool fixed_input = false;  // always input_width x input_height, whatever the scales
};

// nullopt when usable; otherwise what is wrong, naming the field.
std::optional<std::string> validate_dnn_spec(const DnnModelSpec& spec);

struct NetworkInputSize {
  int width = 0;
  int height = 0;
  double scale = 1.0;  // network pixels per frame pixel
  [[nodiscard]] long pixels() const { return static_cast<long>(width) * height; }
};

// The network input for a region of region_width x region_height frame pixels, each
// frame_mm_per_px on the ground: the region resampled so that one network pixel covers the
// model's ground_mm_per_px, each side rounded to the nearest multiple of the stride (at least
// one stride). Where either scale is unknown (0) or the spec is fixed_input, the spec's
// input_width x input_height.
NetworkInputSize network_input_size(const DnnModelSpec& spec, double frame_mm_per_px,
                                    int region_width, int region_height);

// An area on the ground, in cm2, as a count of pixels mm_per_px on a side (at least 1);
// fallback_px where the scale is unknown (mm_per_px = 0).
int area_in_pixels(double area_cm2, double mm_per_px, int fallback_px = 1);

// The 2018 paper's inter-row rule with crop rows tracked from frame to frame. Rows are peaks
// of the (smoothed) column histogram of the vegetation mask; vegetation within a band of
// row_band_fraction of the region's width centred on a row is crop, elsewhere it is weed.
// Positions are fractions of the region's width, so they do not depend on the frame size.
struct InterRowRule {
  double row_band_fraction = 0.16;   // width of a crop-row band / region width
  double peak_fraction = 1.0 / 3.0;  // a peak must exceed this share of the tallest column
  double min_row_spacing = 0.2;      // rows closer than this (share of width) are one row
  double track_gate = 0.08;          // a tracked row accepts a peak this close (share)
  double smoothing = 0.5;            // weight of a new observation in a row's position
  int confirm_frames = 2;            // frames a new row must be seen before it counts
  int lost_after_frames = 10;        // a row unseen this many frames is dropped
};

// nullopt when usable; otherwise what is wrong, naming the field.
std::optional<std::string> validate_inter_row_rule(const InterRowRule& rule);

}  // namespace weedspray::vision
