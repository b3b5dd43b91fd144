// SPDX-License-Identifier: Apache-2.0
// vision-eval --classes / --weed-sources: the weed sources against labelled images.
#pragma once

#include <string>

namespace weedspray::lab {

struct WeedEvalOptions {
  std::string images_dir;
  std::string masks_dir;
  std::string list;                // image stems to evaluate (empty: all)
  bool class_masks = false;        // --classes: masks hold 0 soil, 1 crop, 2 weed
  std::string model;               // ONNX file (its .json sibling gives the spec)
  std::string weed_source;         // only this source (empty: every source that can run)
  std::string config;              // daemon configuration file ([vision], [spray], first camera)
  std::string grid;                // ROWSxCOLS (empty: the configuration's, else 2x4)
  double decision_threshold = -1;  // < 0: the configuration's, else the daemon default
  double weedy_share = 0.005;
  int crop_margin_px = -1;        // < 0: vision.crop_margin_cm at the images' scale (see setup)
  int min_plant_px = -1;          // < 0: vision.min_plant_cm2 at the images' scale
  double row_band_fraction = -1;  // < 0: the configuration's, else InterRowRule's default
  // Ground size of one pixel of the images; 0: the model's training photos' (its JSON's
  // training.dataset_mm_per_px), else unknown (frames squeezed to the network's input size).
  double image_mm_per_px = 0;
  // > 0: the images (and masks) are first resampled to this ground scale, as a camera at that
  // scale would see the same ground (e.g. the daemon's default camera's 1.0077 mm/px).
  double frame_mm_per_px = 0;
  bool sweep = false;  // also the zone trade-off at a range of decision thresholds
  bool json = false;
};

// Hybrid's margin and the least plant on the 960x720 peanut photos where the scale is unknown.
inline constexpr int kDefaultCropMarginPx = 3;
inline constexpr int kDefaultMinPlantPx = 9;

int run_weed_eval(const WeedEvalOptions& options);

}  // namespace weedspray::lab
