// SPDX-License-Identifier: Apache-2.0
#include "lab/weed_eval.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace weedspray::lab {

cv::Mat class_map_at_region_size(vision::Pipeline& pipeline) {
  const vision::ImageView map = pipeline.class_map();
  const cv::Mat classes(map.height, map.width, CV_8UC1, const_cast<std::uint8_t*>(map.data),
                        map.stride);
  const cv::Size region(pipeline.region().width, pipeline.region().height);
  cv::Mat out;
  if (classes.size() == region) {
    classes.copyTo(out);
  } else {  // dnn: the network's resolution
    cv::resize(classes, out, region, 0, 0, cv::INTER_NEAREST);
  }
  return out;
}

WeedEvalRow evaluate_weed_source(const std::vector<LabelledImage>& images,
                                 vision::PipelineConfig config,
                                 std::span<const std::uint8_t> model_onnx, const ZoneRule& rule,
                                 bool class_masks) {
  config.rows = rule.rows;
  config.cols = rule.cols;
  vision::Pipeline pipeline(config, model_onnx);
  WeedEvalRow row;
  row.source = config.weed_source;
  row.rule = rule;
  ConfusionMatrix confusion;
  for (const LabelledImage& image : images) {
    pipeline.reset_tracking();
    const vision::ImageView view{image.bgr.data, image.bgr.cols, image.bgr.rows, image.bgr.step[0],
                                 vision::PixelFormat::kBgr24};
    const auto start = std::chrono::steady_clock::now();
    const vision::FrameResult& result = pipeline.process(view);
    const auto stop = std::chrono::steady_clock::now();
    row.ms_per_image += std::chrono::duration<double, std::milli>(stop - start).count();
    if (!pipeline.last_frame_ok()) {
      throw std::runtime_error(image.name + ": " + std::string(to_string(config.weed_source)) +
                               " failed: " + pipeline.last_error());
    }
    const vision::PixelRect r = pipeline.region();
    const cv::Rect region(r.x, r.y, r.width, r.height);
    const cv::Mat predicted = class_map_at_region_size(pipeline);

    const cv::Mat predicted_plant = predicted != vision::kClassSoil;
    const cv::Mat plant = image.plant(region);
    const double union_count = cv::countNonZero(predicted_plant | plant);
    row.vegetation_iou +=
        union_count == 0 ? 1.0 : cv::countNonZero(predicted_plant & plant) / union_count;

    if (class_masks) {
      const cv::Mat truth = image.mask(region);
      try {
        row.image_confusion.emplace_back().add(truth, predicted);
        confusion.add(truth, predicted);
      } catch (const std::invalid_argument& error) {
        throw std::runtime_error(image.name + ": mask is not class ids 0 soil, 1 crop, 2 weed (" +
                                 error.what() + ")");
      }
      add_zone_samples(truth, result.densities(), rule.rows, rule.cols, row.zone_samples);
    }
  }
  const double n = static_cast<double>(images.size());
  row.ms_per_image /= n;
  row.vegetation_iou /= n;
  if (class_masks) {
    row.scores = class_scores(confusion);
    row.zones = tally_zones(row.zone_samples, rule);
  }
  return row;
}

// The images and masks as a camera of frame_mm_per_px would see the same ground: images
// averaged (INTER_AREA, or INTER_LINEAR when enlarged), masks' class ids kept (nearest).
void resample_to_scale(std::vector<LabelledImage>& images, double image_mm_per_px,
                       double frame_mm_per_px) {
  const double factor = image_mm_per_px / frame_mm_per_px;
  const int interpolation = factor < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR;
  for (LabelledImage& image : images) {
    const cv::Size size(std::max(2, static_cast<int>(std::lround(image.bgr.cols * factor))),
                        std::max(2, static_cast<int>(std::lround(image.bgr.rows * factor))));
    cv::resize(image.bgr, image.bgr, size, 0, 0, interpolation);
    cv::resize(image.plant, image.plant, size, 0, 0, cv::INTER_NEAREST);
    cv::resize(image.mask, image.mask, size, 0, 0, cv::INTER_NEAREST);
  }
}

int crop_margin_px_at(double crop_margin_cm, double image_mm_per_px, int fallback_px) {
  if (!(image_mm_per_px > 0)) return fallback_px;
  return static_cast<int>(std::lround(crop_margin_cm * 10.0 / image_mm_per_px));
}

ImageIntervals image_intervals(const WeedEvalRow& row) {
  constexpr int kDraws = 1000;
  const std::size_t images = row.image_confusion.size();
  const std::size_t zones = static_cast<std::size_t>(row.rule.rows * row.rule.cols);
  ImageIntervals out;
  if (images == 0 || row.zone_samples.size() != images * zones) return out;
  std::mt19937 random(20261127);
  std::uniform_int_distribution<std::size_t> pick(0, images - 1);
  std::array<std::vector<double>, 6> draws;
  std::vector<ZoneSample> samples;
  for (int d = 0; d < kDraws; ++d) {
    ConfusionMatrix confusion;
    samples.clear();
    for (std::size_t i = 0; i < images; ++i) {
      const std::size_t image = pick(random);
      for (int t = 0; t < kClassCount; ++t) {
        for (int p = 0; p < kClassCount; ++p) {
          confusion.counts[t][p] += row.image_confusion[image].counts[t][p];
        }
      }
      const auto first = row.zone_samples.begin() + static_cast<std::ptrdiff_t>(image * zones);
      samples.insert(samples.end(), first, first + static_cast<std::ptrdiff_t>(zones));
    }
    const ClassScores scores = class_scores(confusion);
    const ZoneTally tally = tally_zones(samples, row.rule);
    const std::array<double, 6> figures = {scores.miou,
                                           scores.iou[1],
                                           scores.iou[2],
                                           tally.recall(),
                                           tally.crop_only_left_dry(),
                                           tally.bare_left_dry()};
    for (std::size_t f = 0; f < figures.size(); ++f) draws[f].push_back(figures[f]);
  }
  const auto interval = [](std::vector<double>& values) {
    std::sort(values.begin(), values.end());
    const auto at = [&](double q) {
      return values[static_cast<std::size_t>(q * static_cast<double>(values.size() - 1))];
    };
    return std::array<double, 2>{at(0.025), at(0.975)};
  };
  out.miou = interval(draws[0]);
  out.crop_iou = interval(draws[1]);
  out.weed_iou = interval(draws[2]);
  out.recall = interval(draws[3]);
  out.crop_only_left_dry = interval(draws[4]);
  out.bare_left_dry = interval(draws[5]);
  return out;
}

}  // namespace weedspray::lab
