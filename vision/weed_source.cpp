// SPDX-License-Identifier: Apache-2.0
#include "vision/weed_source.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace weedspray::vision {
namespace {

constexpr std::array<std::string_view, 6> kNames = {"vegetation", "inter_row", "dnn",
                                                    "hybrid",     "plants",    "dnn_vegetation"};

}  // namespace

std::optional<WeedSource> parse_weed_source(std::string_view name) {
  for (std::size_t i = 0; i < kNames.size(); ++i) {
    if (kNames[i] == name) return static_cast<WeedSource>(i);
  }
  return std::nullopt;
}

std::string_view to_string(WeedSource source) {
  const auto i = static_cast<std::size_t>(source);
  return i < kNames.size() ? kNames[i] : "unknown";
}

std::span<const std::string_view> weed_source_names() {
  return kNames;
}

bool needs_model(WeedSource source) {
  return source == WeedSource::kDnn || source == WeedSource::kHybrid ||
         source == WeedSource::kPlants || source == WeedSource::kDnnVegetation;
}

int area_in_pixels(double area_cm2, double mm_per_px, int fallback_px) {
  if (!(mm_per_px > 0.0)) return fallback_px;
  const double pixels = area_cm2 * 100.0 / (mm_per_px * mm_per_px);
  return static_cast<int>(std::clamp(std::lround(pixels), 1L, 1000000L));
}

std::optional<std::string> validate_dnn_spec(const DnnModelSpec& spec) {
  // Larger inputs cost far more than a camera frame's time on the sprayer's boards.
  constexpr int kMaxSide = 4096;
  if (spec.input_width < 1 || spec.input_width > kMaxSide || spec.input_height < 1 ||
      spec.input_height > kMaxSide) {
    return "dnn input size must lie in [1, " + std::to_string(kMaxSide) + "] (got " +
           std::to_string(spec.input_width) + "x" + std::to_string(spec.input_height) + ")";
  }
  if (!(spec.scale > 0.0)) return "dnn scale must be > 0";
  if (spec.stride < 1 || spec.stride > 256) return "dnn stride must lie in [1, 256]";
  if (spec.input_width % spec.stride != 0 || spec.input_height % spec.stride != 0) {
    return "dnn input size " + std::to_string(spec.input_width) + "x" +
           std::to_string(spec.input_height) + " is not a multiple of the network's stride " +
           std::to_string(spec.stride);
  }
  if (spec.input_channels != 3) {
    return "dnn input_channels = " + std::to_string(spec.input_channels) +
           ": the pipeline feeds 3 colour channels";
  }
  if (!(spec.ground_mm_per_px >= 0.0)) return "dnn ground_mm_per_px must be >= 0 (0 = unknown)";
  const int classes = static_cast<int>(spec.classes.size());
  if (classes < 2) return "dnn classes must list at least 2 classes";
  const std::array<std::pair<const char*, int>, 3> ids = {{{"soil_class", spec.soil_class},
                                                           {"crop_class", spec.crop_class},
                                                           {"weed_class", spec.weed_class}}};
  for (const auto& [name, id] : ids) {
    if (id < 0 || id >= classes) {
      return std::string("dnn ") + name + " = " + std::to_string(id) + " is not a class id (0.." +
             std::to_string(classes - 1) + " for " + std::to_string(classes) + " classes)";
    }
  }
  if (spec.crop_class == spec.weed_class || spec.crop_class == spec.soil_class ||
      spec.weed_class == spec.soil_class) {
    return "dnn soil_class, crop_class and weed_class must be different class ids";
  }
  return std::nullopt;
}

NetworkInputSize network_input_size(const DnnModelSpec& spec, double frame_mm_per_px,
                                    int region_width, int region_height) {
  if (spec.fixed_input || !(spec.ground_mm_per_px > 0.0) || !(frame_mm_per_px > 0.0) ||
      region_width < 1 || region_height < 1) {
    const double scale =
        region_width > 0 ? static_cast<double>(spec.input_width) / region_width : 1.0;
    return {spec.input_width, spec.input_height, scale};
  }
  const double scale = frame_mm_per_px / spec.ground_mm_per_px;
  const int stride = std::max(1, spec.stride);
  const auto side = [&](int frame_px) {
    const long steps = std::lround(frame_px * scale / stride);
    return static_cast<int>(std::max(1L, steps) * stride);
  };
  return {side(region_width), side(region_height), scale};
}

std::optional<std::string> validate_inter_row_rule(const InterRowRule& rule) {
  if (!(rule.row_band_fraction > 0.0 && rule.row_band_fraction < 1.0)) {
    return "inter_row row_band_fraction must lie in (0, 1)";
  }
  if (!(rule.peak_fraction > 0.0 && rule.peak_fraction < 1.0)) {
    return "inter_row peak_fraction must lie in (0, 1)";
  }
  if (!(rule.min_row_spacing > 0.0 && rule.min_row_spacing < 1.0)) {
    return "inter_row min_row_spacing must lie in (0, 1)";
  }
  if (!(rule.track_gate > 0.0 && rule.track_gate < 1.0)) {
    return "inter_row track_gate must lie in (0, 1)";
  }
  if (!(rule.smoothing > 0.0 && rule.smoothing <= 1.0)) {
    return "inter_row smoothing must lie in (0, 1]";
  }
  if (rule.confirm_frames < 1) return "inter_row confirm_frames must be >= 1";
  if (rule.lost_after_frames < 1) return "inter_row lost_after_frames must be >= 1";
  return std::nullopt;
}

}  // namespace weedspray::vision
