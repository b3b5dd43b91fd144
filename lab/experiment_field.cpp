// SPDX-License-Identifier: Apache-2.0
#include "lab/experiment_field.hpp"

#include <opencv2/core.hpp>
#include <stdexcept>

namespace weedspray::lab {

namespace ex = lab::experiments;

std::vector<std::array<ex::ZoneTruth, kFieldNozzles>> mask_zone_truth(const cv::Mat& class_mask) {
  if (class_mask.empty() || class_mask.type() != CV_8UC1) {
    throw std::invalid_argument("mask_zone_truth: an 8-bit one-channel class-id mask is needed");
  }
  // Row 0 is the top of the frame: the ground farther ahead, reached later. Travel order is
  // therefore the near (bottom) row first. Zone bounds as vision::Pipeline computes them.
  std::vector<std::array<ex::ZoneTruth, kFieldNozzles>> rows;
  for (int row = kFieldZoneRows - 1; row >= 0; --row) {
    const int y_begin = row * class_mask.rows / kFieldZoneRows;
    const int y_end = (row + 1) * class_mask.rows / kFieldZoneRows;
    std::array<ex::ZoneTruth, kFieldNozzles> zones{};
    for (int col = 0; col < kFieldNozzles; ++col) {
      const int x_begin = col * class_mask.cols / kFieldNozzles;
      const int x_end = (col + 1) * class_mask.cols / kFieldNozzles;
      const cv::Mat zone = class_mask(cv::Range(y_begin, y_end), cv::Range(x_begin, x_end));
      const double pixels = static_cast<double>(zone.total());
      zones[static_cast<std::size_t>(col)] = {cv::countNonZero(zone == 2) / pixels,
                                              cv::countNonZero(zone == 1) / pixels};
    }
    rows.push_back(zones);
  }
  return rows;
}

LabelledField labelled_field(const std::vector<LabelledImage>& images,
                             const std::optional<vision::PipelineConfig>& source,
                             std::span<const std::uint8_t> model_onnx) {
  std::optional<vision::Pipeline> pipeline;
  if (source) {
    vision::PipelineConfig config = *source;
    config.rows = kFieldZoneRows;
    config.cols = kFieldNozzles;
    pipeline.emplace(config, model_onnx);
  }
  LabelledField field;
  for (const LabelledImage& image : images) {
    const auto truth = mask_zone_truth(image.mask);
    field.truth.insert(field.truth.end(), truth.begin(), truth.end());
    if (!pipeline) {
      for (const auto& row : truth) {
        std::array<double, kFieldNozzles> weed{};
        for (int col = 0; col < kFieldNozzles; ++col) weed[col] = row[col].weed;
        field.weed_density.push_back(weed);
      }
      continue;
    }
    pipeline->reset_tracking();  // the photos are not consecutive frames
    const vision::FrameResult& r =
        pipeline->process({image.bgr.data, image.bgr.cols, image.bgr.rows, image.bgr.step[0],
                           vision::PixelFormat::kBgr24});
    if (!pipeline->last_frame_ok()) {
      throw std::runtime_error(image.name +
                               ": the vision pipeline failed: " + pipeline->last_error());
    }
    for (int row = r.rows - 1; row >= 0; --row) {
      std::array<double, kFieldNozzles> weed{};
      for (int col = 0; col < kFieldNozzles; ++col) weed[col] = r.density(row, col);
      field.weed_density.push_back(weed);
    }
  }
  return field;
}

}  // namespace weedspray::lab
