// SPDX-License-Identifier: Apache-2.0
#include "lab/class_metrics.hpp"

#include <stdexcept>

namespace weedspray::lab {

void ConfusionMatrix::add(const cv::Mat& truth, const cv::Mat& predicted) {
  if (truth.size() != predicted.size() || truth.type() != CV_8UC1 || predicted.type() != CV_8UC1) {
    throw std::invalid_argument("confusion matrix: truth and prediction differ in size or type");
  }
  for (int y = 0; y < truth.rows; ++y) {
    const std::uint8_t* t = truth.ptr<std::uint8_t>(y);
    const std::uint8_t* p = predicted.ptr<std::uint8_t>(y);
    for (int x = 0; x < truth.cols; ++x) {
      if (t[x] >= kClassCount || p[x] >= kClassCount) {
        throw std::invalid_argument("confusion matrix: class id " +
                                    std::to_string(std::max(t[x], p[x])) + " out of range");
      }
      ++counts[t[x]][p[x]];
    }
  }
}

ClassScores class_scores(const ConfusionMatrix& confusion) {
  ClassScores scores;
  for (int c = 0; c < kClassCount; ++c) {
    std::uint64_t truth = 0;
    std::uint64_t predicted = 0;
    for (int k = 0; k < kClassCount; ++k) {
      truth += confusion.counts[c][k];
      predicted += confusion.counts[k][c];
    }
    const std::uint64_t hit = confusion.counts[c][c];
    const std::uint64_t union_count = truth + predicted - hit;
    scores.iou[c] = union_count == 0 ? 1.0 : static_cast<double>(hit) / union_count;
    scores.pixel_accuracy[c] = truth == 0 ? 1.0 : static_cast<double>(hit) / truth;
    scores.miou += scores.iou[c] / kClassCount;
    scores.mpa += scores.pixel_accuracy[c] / kClassCount;
  }
  return scores;
}

bool would_spray(double weed_density, double decision_threshold) {
  // control/spray_rate_law.cpp: nothing is sprayed when density <= 0 or < the threshold.
  return weed_density > 0.0 && weed_density >= decision_threshold;
}

cv::Rect zone_rect(int row, int col, int rows, int cols, cv::Size size) {
  const int x0 = col * size.width / cols;
  const int x1 = (col + 1) * size.width / cols;
  const int y0 = row * size.height / rows;
  const int y1 = (row + 1) * size.height / rows;
  return {x0, y0, x1 - x0, y1 - y0};
}

void add_zone_samples(const cv::Mat& truth, std::span<const double> weed_density, int rows,
                      int cols, std::vector<ZoneSample>& samples) {
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      const cv::Rect zone = zone_rect(row, col, rows, cols, truth.size());
      const double area = zone.area();
      const double weed = cv::countNonZero(truth(zone) == 2) / area;
      const double crop = cv::countNonZero(truth(zone) == 1) / area;
      samples.push_back({weed, weed_density[static_cast<std::size_t>(row * cols + col)], crop});
    }
  }
}

ZoneTally tally_zones(std::span<const ZoneSample> samples, const ZoneRule& rule) {
  ZoneTally tally;
  for (const ZoneSample& zone : samples) {
    const bool sprayed = would_spray(zone.weed_density, rule.decision_threshold);
    if (zone.true_weed_share >= rule.weedy_share) {
      ++tally.weedy;
      tally.weedy_sprayed += sprayed;
    } else {
      ++tally.clean;
      tally.clean_dry += !sprayed;
      if (zone.true_crop_share >= rule.weedy_share) {
        ++tally.crop_only;
        tally.crop_only_dry += !sprayed;
      } else {
        ++tally.bare;
        tally.bare_dry += !sprayed;
      }
    }
  }
  return tally;
}

}  // namespace weedspray::lab
