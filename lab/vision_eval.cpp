// SPDX-License-Identifier: Apache-2.0
#include "lab/vision_eval.hpp"

#include <array>
#include <chrono>
#include <cmath>

namespace weedspray::lab {
namespace {

vision::ImageView view_of(const cv::Mat& bgr) {
  return {bgr.data, bgr.cols, bgr.rows, bgr.step[0], vision::PixelFormat::kBgr24};
}

struct ImageOutcome {
  double iou = 0;
  int threshold = 0;
  double vegetation_pct = 0;
  double ms = 0;
};

}  // namespace

double plant_iou(const vision::ImageView& index_image, int threshold, const cv::Mat& plant) {
  std::uint64_t intersection = 0;
  std::uint64_t union_count = 0;
  for (int y = 0; y < index_image.height; ++y) {
    const std::uint8_t* index_row = index_image.data + y * index_image.stride;
    const std::uint8_t* label_row = plant.ptr<std::uint8_t>(y);
    for (int x = 0; x < index_image.width; ++x) {
      const bool predicted = index_row[x] > threshold;
      const bool labelled = label_row[x] != 0;
      intersection += predicted && labelled;
      union_count += predicted || labelled;
    }
  }
  return union_count == 0 ? 1.0 : static_cast<double>(intersection) / union_count;
}

std::vector<EvalRow> evaluate_combinations(const std::vector<LabelledImage>& images,
                                           std::span<const vision::VegetationIndex> indices,
                                           std::span<const vision::ThresholdMethod> methods,
                                           const vision::PipelineConfig& base) {
  std::vector<EvalRow> rows;
  for (const vision::VegetationIndex index : indices) {
    // Otsu on the same index is the reference of eps and rho.
    vision::PipelineConfig otsu_config = base;
    otsu_config.index = index;
    otsu_config.threshold = vision::ThresholdMethod::kOtsu;
    otsu_config.rows = otsu_config.cols = 1;
    vision::Pipeline otsu(otsu_config);
    std::vector<ImageOutcome> reference;
    for (const LabelledImage& image : images) {
      const vision::FrameResult& result = otsu.process(view_of(image.bgr));
      reference.push_back({0, result.threshold, 100.0 * result.vegetation_fraction, 0});
    }
    for (const vision::ThresholdMethod method : methods) {
      vision::PipelineConfig config = otsu_config;
      config.threshold = method;
      vision::Pipeline pipeline(config);
      pipeline.process(view_of(images.front().bgr));  // warm-up: buffers and tables
      EvalRow row{index, method};
      for (std::size_t i = 0; i < images.size(); ++i) {
        const auto start = std::chrono::steady_clock::now();
        const vision::FrameResult& result = pipeline.process(view_of(images[i].bgr));
        const auto stop = std::chrono::steady_clock::now();
        row.ms_per_image += std::chrono::duration<double, std::milli>(stop - start).count();
        row.mean_iou += plant_iou(pipeline.index_image(), result.threshold, images[i].plant);
        row.mean_threshold += result.threshold;
        row.threshold_error += std::abs(result.threshold - reference[i].threshold);
        row.precision_pct +=
            std::abs(100.0 * result.vegetation_fraction - reference[i].vegetation_pct);
      }
      const double n = static_cast<double>(images.size());
      row.ms_per_image /= n;
      row.mean_iou /= n;
      row.mean_threshold /= n;
      row.threshold_error /= n;
      row.precision_pct = 100.0 - row.precision_pct / n;
      rows.push_back(row);
    }
  }
  return rows;
}

IndexBounds index_bounds(const std::vector<LabelledImage>& images, vision::VegetationIndex index) {
  vision::PipelineConfig config;
  config.index = index;
  config.rows = config.cols = 1;
  vision::Pipeline pipeline(config);
  std::array<double, 256> iou_sum_per_threshold{};
  IndexBounds bounds;
  for (const LabelledImage& image : images) {
    pipeline.process(view_of(image.bgr));
    const vision::ImageView index_image = pipeline.index_image();
    // Plant and soil histograms of the index give the IoU of every threshold at once.
    std::array<std::uint64_t, 256> plant{}, soil{};
    for (int y = 0; y < index_image.height; ++y) {
      const std::uint8_t* index_row = index_image.data + y * index_image.stride;
      const std::uint8_t* label_row = image.plant.ptr<std::uint8_t>(y);
      for (int x = 0; x < index_image.width; ++x) {
        ++(label_row[x] ? plant : soil)[index_row[x]];
      }
    }
    std::uint64_t plant_total = 0;
    for (auto count : plant) plant_total += count;
    double best = 0;
    std::uint64_t plant_above = 0, soil_above = 0;
    for (int t = 255; t >= 0; --t) {
      // pixels > t
      const std::uint64_t union_count = plant_total + soil_above;
      const double iou = union_count == 0 ? 1.0 : static_cast<double>(plant_above) / union_count;
      iou_sum_per_threshold[t] += iou;
      best = std::max(best, iou);
      plant_above += plant[t];
      soil_above += soil[t];
    }
    bounds.oracle_iou += best;
  }
  bounds.oracle_iou /= images.size();
  for (int t = 0; t < 256; ++t) {
    const double mean = iou_sum_per_threshold[t] / images.size();
    if (mean > bounds.best_fixed_iou) {
      bounds.best_fixed_iou = mean;
      bounds.best_fixed = t;
    }
  }
  return bounds;
}

}  // namespace weedspray::lab
