// SPDX-License-Identifier: Apache-2.0
#include "vision/weed_classifier.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <opencv2/imgproc.hpp>

#include "vision/weed_network.hpp"
#include "vision/zone_counts.hpp"

namespace weedspray::vision {

struct WeedClassifier::Masks {
  cv::Mat converted;         // the region as BGR when the frame is YUYV or grey
  cv::Mat vegetation;        // hybrid, plants, dnn_vegetation: region resolution, 0/255
  cv::Mat near_crop;         // hybrid: the network's crop at region resolution, grown by the margin
  cv::Mat crop;              // hybrid: vegetation within near_crop; else the class map's crop
  cv::Mat plant_classes;     // plants, dnn_vegetation: class ids at region resolution
  cv::Mat grown;             // dnn_vegetation: vegetation grown by the plants' join
  cv::Mat network_interior;  // dnn_vegetation: the network's plant less its outer pixel
  cv::Mat weed;              // hybrid: vegetation outside near_crop; else the class map's weed
  cv::Mat margin_kernel;
  cv::Mat scratch;
};

namespace {

struct ZoneRect {
  int x_begin, x_end, y_begin, y_end;
  double pixels() const { return static_cast<double>(x_end - x_begin) * (y_end - y_begin); }
  cv::Rect rect() const { return {x_begin, y_begin, x_end - x_begin, y_end - y_begin}; }
};

// Plants are the colour vegetation grown by about a millimetre on the ground (1 px where the
// scale is unknown).
int plant_join_px(double frame_mm_per_px) {
  constexpr double kJoinMm = 1.0;
  return frame_mm_per_px > 0.0
             ? std::max(1, static_cast<int>(std::lround(kJoinMm / frame_mm_per_px)))
             : 1;
}

// Zone (row, col) of a rows x cols grid over a width x height image, as Pipeline cuts it.
ZoneRect zone_rect(int row, int col, int rows, int cols, int width, int height) {
  return {col * width / cols, (col + 1) * width / cols, row * height / rows,
          (row + 1) * height / rows};
}

// The region of the frame as a CV_8UC3 image (no copy for BGR/RGB frames).
cv::Mat region_image(const ImageView& frame, const PixelRect& region, cv::Mat& converted,
                     bool& is_rgb) {
  auto* data = const_cast<std::uint8_t*>(frame.data);  // read only: OpenCV's headers are not const
  const cv::Rect rect(region.x, region.y, region.width, region.height);
  is_rgb = frame.format == PixelFormat::kRgb24;
  switch (frame.format) {
    case PixelFormat::kBgr24:
    case PixelFormat::kRgb24:
      return cv::Mat(frame.height, frame.width, CV_8UC3, data, frame.stride)(rect);
    case PixelFormat::kYuyv:
      cv::cvtColor(cv::Mat(frame.height, frame.width, CV_8UC2, data, frame.stride)(rect), converted,
                   cv::COLOR_YUV2BGR_YUYV);
      return converted;
    case PixelFormat::kGrey:
      cv::cvtColor(cv::Mat(frame.height, frame.width, CV_8UC1, data, frame.stride)(rect), converted,
                   cv::COLOR_GRAY2BGR);
      return converted;
  }
  return converted;
}

// Weed and crop shares of each zone from masks (non-zero = weed, crop) of one size.
void count_zone_densities(const cv::Mat& weed, const cv::Mat& crop, FrameResult& result) {
  for (int row = 0; row < result.rows; ++row) {
    for (int col = 0; col < result.cols; ++col) {
      const ZoneRect zone = zone_rect(row, col, result.rows, result.cols, weed.cols, weed.rows);
      const int i = row * result.cols + col;
      const double pixels = std::max(1.0, zone.pixels());
      result.zone_density[i] = cv::countNonZero(weed(zone.rect())) / pixels;
      result.crop_density[i] = cv::countNonZero(crop(zone.rect())) / pixels;
    }
  }
}

// Weed and crop shares of each zone of a class map; weed and crop are scratch masks (sized once
// per class-map size, so a steady stream allocates nothing).
void densities_from_classes(const cv::Mat& classes, cv::Mat& weed, cv::Mat& crop,
                            FrameResult& result) {
  cv::compare(classes, kClassWeed, weed, cv::CMP_EQ);
  cv::compare(classes, kClassCrop, crop, cv::CMP_EQ);
  count_zone_densities(weed, crop, result);
}

}  // namespace

WeedClassifier::WeedClassifier(const PipelineConfig& config,
                               std::span<const std::uint8_t> model_onnx_bytes)
    : config_(config),
      tracker_(config.inter_row_rule),
      plants_(config.min_plant_px, plant_join_px(config.frame_mm_per_px)),
      masks_(std::make_unique<Masks>()) {
  if (needs_model(config_.weed_source)) {
    network_ =
        std::make_unique<WeedNetwork>(config_.dnn, model_onnx_bytes, config_.frame_mm_per_px);
  }
  if (config_.crop_margin_px > 0) {
    const int side = 2 * config_.crop_margin_px + 1;
    masks_->margin_kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(side, side));
  }
}

WeedClassifier::~WeedClassifier() = default;

bool WeedClassifier::classify(const ImageView& frame, const PixelRect& region,
                              const std::uint8_t* index, std::uint8_t level, FrameResult& result,
                              std::string& error) {
  region_ = region;
  try {
    switch (config_.weed_source) {
      case WeedSource::kVegetation:
        break;
      case WeedSource::kInterRow:
        classify_inter_row(index, level, result);
        break;
      case WeedSource::kDnn:
        run_network(frame);
        densities_from_classes(network_classes(), masks_->weed, masks_->crop, result);
        break;
      case WeedSource::kHybrid:
        run_network(frame);
        classify_hybrid(index, level, result);
        break;
      case WeedSource::kPlants:
        run_network(frame);
        classify_plants(index, level, result);
        break;
      case WeedSource::kDnnVegetation:
        run_network(frame);
        classify_dnn_vegetation(index, level, result);
        break;
    }
  } catch (const std::exception& failure) {
    error = std::string("weed source ") + std::string(to_string(config_.weed_source)) +
            " failed: " + failure.what();
    return false;
  }
  return true;
}

void WeedClassifier::classify_inter_row(const std::uint8_t* index, std::uint8_t level,
                                        FrameResult& result) {
  const int width = region_.width;
  const auto columns = static_cast<std::size_t>(width);
  // Grows only when a wider frame arrives; steady state allocates nothing.
  zone_row_columns_.resize(columns * (result.rows + 1));
  std::fill(zone_row_columns_.begin(), zone_row_columns_.end(), 0u);
  std::uint32_t* total = zone_row_columns_.data() + columns * result.rows;
  for (int row = 0; row < result.rows; ++row) {
    std::uint32_t* counts = zone_row_columns_.data() + columns * row;
    const ZoneRect rows = zone_rect(row, 0, result.rows, 1, width, region_.height);
    for (int y = rows.y_begin; y < rows.y_end; ++y) {
      accumulate_columns_above(index + static_cast<std::size_t>(y) * width, width, level, counts);
    }
    for (std::size_t x = 0; x < columns; ++x) total[x] += counts[x];
  }
  tracker_.update({total, columns});
  in_band_.resize(columns);
  tracker_.mark_bands(in_band_);

  for (int row = 0; row < result.rows; ++row) {
    const std::uint32_t* counts = zone_row_columns_.data() + columns * row;
    for (int col = 0; col < result.cols; ++col) {
      const ZoneRect zone = zone_rect(row, col, result.rows, result.cols, width, region_.height);
      std::uint64_t weed = 0;
      std::uint64_t crop = 0;
      for (int x = zone.x_begin; x < zone.x_end; ++x) (in_band_[x] ? crop : weed) += counts[x];
      const int i = row * result.cols + col;
      result.zone_density[i] = static_cast<double>(weed) / zone.pixels();
      result.crop_density[i] = static_cast<double>(crop) / zone.pixels();
    }
  }
}

void WeedClassifier::run_network(const ImageView& frame) {
  bool is_rgb = false;
  const cv::Mat image = region_image(frame, region_, masks_->converted, is_rgb);
  network_->segment(image, is_rgb);
}

const cv::Mat& WeedClassifier::network_classes() {
  return network_->classes_at(cv::Size(region_.width, region_.height));
}

const cv::Mat& WeedClassifier::vegetation_mask(const std::uint8_t* index, std::uint8_t level) {
  const cv::Mat index_image(region_.height, region_.width, CV_8UC1,
                            const_cast<std::uint8_t*>(index));
  cv::compare(index_image, level, masks_->vegetation, cv::CMP_GT);
  return masks_->vegetation;
}

void WeedClassifier::classify_hybrid(const std::uint8_t* index, std::uint8_t level,
                                     FrameResult& result) {
  Masks& m = *masks_;
  vegetation_mask(index, level);
  // Colour says what is vegetation, the network only which of it is crop: the vegetation
  // mask (and its IoU) stays the colour pipeline's on any camera. The margin is in frame
  // pixels.
  cv::compare(network_classes(), kClassCrop, m.near_crop, cv::CMP_EQ);
  if (!m.margin_kernel.empty()) cv::dilate(m.near_crop, m.near_crop, m.margin_kernel);
  cv::bitwise_and(m.vegetation, m.near_crop, m.crop);
  cv::bitwise_xor(m.vegetation, m.crop, m.weed);  // vegetation minus crop
  count_zone_densities(m.weed, m.crop, result);
}

void WeedClassifier::classify_plants(const std::uint8_t* index, std::uint8_t level,
                                     FrameResult& result) {
  Masks& m = *masks_;
  // The network votes on its own grid: the rule's neighbourhood is one network pixel.
  plants_.classify(vegetation_mask(index, level), network_->segment_result(), m.plant_classes);
  densities_from_classes(m.plant_classes, m.weed, m.crop, result);
}

void WeedClassifier::classify_dnn_vegetation(const std::uint8_t* index, std::uint8_t level,
                                             FrameResult& result) {
  Masks& m = *masks_;
  // Grown as the plants source joins its plants: the soft leaf edge colour leaves out is plant.
  plants_.join(vegetation_mask(index, level), m.grown);
  // Colour trims only the outer network pixel of what the network calls plant, where its grid
  // blurs the edge; further in, the network's class stands whatever colour says (a shaded leaf,
  // a camera whose plants the threshold finds poorly).
  cv::compare(network_->segment_result(), kClassSoil, m.network_interior, cv::CMP_NE);
  cv::erode(m.network_interior, m.network_interior, cv::Mat(), cv::Point(-1, -1), 1,
            cv::BORDER_REPLICATE);
  cv::resize(m.network_interior, m.scratch, m.grown.size(), 0, 0, cv::INTER_NEAREST);
  cv::bitwise_or(m.grown, m.scratch, m.grown);
  // grown is 0 or 255 and soil is class 0: the AND keeps the class on vegetation, soil elsewhere.
  static_assert(kClassSoil == 0);
  cv::bitwise_and(network_classes(), m.grown, m.plant_classes);
  densities_from_classes(m.plant_classes, m.weed, m.crop, result);
}

PixelRect WeedClassifier::network_input() const {
  if (!network_) return {};
  const cv::Size size = network_->input_size();
  return {0, 0, size.width, size.height};
}

ImageView WeedClassifier::class_map(const std::uint8_t* index, std::uint8_t level,
                                    std::span<std::uint8_t> out) {
  Masks& m = *masks_;
  const cv::Size size(region_.width, region_.height);
  // A header on the caller's bytes: the writes below fill it in place, allocating nothing.
  cv::Mat map(size, CV_8UC1, out.data());
  switch (config_.weed_source) {
    case WeedSource::kVegetation:
      break;
    case WeedSource::kInterRow:
      for (int y = 0; y < size.height; ++y) {
        const std::uint8_t* values = index + static_cast<std::size_t>(y) * size.width;
        std::uint8_t* row = map.ptr<std::uint8_t>(y);
        for (int x = 0; x < size.width; ++x) {
          row[x] = values[x] <= level ? kClassSoil : in_band_[x] ? kClassCrop : kClassWeed;
        }
      }
      break;
    case WeedSource::kDnn:
      network_classes().copyTo(map);
      break;
    case WeedSource::kHybrid:
      // Vegetation kept out of the weeds by the margin is attributed to the crop.
      map.setTo(kClassSoil);
      map.setTo(kClassCrop, m.crop);
      map.setTo(kClassWeed, m.weed);
      break;
    case WeedSource::kPlants:
    case WeedSource::kDnnVegetation:
      m.plant_classes.copyTo(map);
      break;
  }
  return {out.data(), size.width, size.height, static_cast<std::size_t>(size.width),
          PixelFormat::kGrey};
}

}  // namespace weedspray::vision
