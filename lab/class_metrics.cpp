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

void tally_zones(const cv::Mat& truth, std::span<const double> weed_density, const ZoneRule& rule,
                 ZoneTally& tally) {
  for (int row = 0; row < rule.rows; ++row) {
    for (int col = 0; col < rule.cols; ++col) {
      const cv::Rect zone = zone_rect(row, col, rule.rows, rule.cols, truth.size());
      const cv::Mat weed = truth(zone) == 2;
      const double share = static_cast<double>(cv::countNonZero(weed)) / zone.area();
      const bool sprayed = would_spray(
          weed_density[static_cast<std::size_t>(row * rule.cols + col)], rule.decision_threshold);
      if (share >= rule.weedy_share) {
        ++tally.weedy;
        tally.weedy_sprayed += sprayed;
      } else {
        ++tally.clean;
        tally.clean_dry += !sprayed;
      }
    }
  }
}

}  // namespace weedspray::lab
