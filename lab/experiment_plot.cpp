// SPDX-License-Identifier: Apache-2.0
#include "lab/experiment_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace weedspray::lab {
namespace {

cv::Scalar bgr(int rgb) {
  return {double(rgb & 0xff), double((rgb >> 8) & 0xff), double(rgb >> 16)};
}

// "Nice" tick step for a range: 1, 2 or 5 times a power of ten, about 6 ticks.
double tick_step(double range) {
  const double raw = range / 6.0;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / mag;
  return (r < 1.5 ? 1.0 : r < 3.5 ? 2.0 : r < 7.5 ? 5.0 : 10.0) * mag;
}

std::string format_tick(double v, double step) {
  char buf[32];
  const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step))));
  std::snprintf(buf, sizeof buf, "%.*f", decimals, std::abs(v) < 1e-6 * step ? 0.0 : v);
  return buf;
}

}  // namespace

void write_plot_png(const PlotSpec& spec, const std::string& path) {
  double x0 = std::numeric_limits<double>::max(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const auto& s : spec.series) {
    for (double v : s.x) x0 = std::min(x0, v), x1 = std::max(x1, v);
    for (double v : s.y) y0 = std::min(y0, v), y1 = std::max(y1, v);
  }
  if (x1 <= x0) x1 = x0 + 1.0;
  if (y1 <= y0) y1 = y0 + 1.0;
  const double ypad = 0.05 * (y1 - y0);
  y0 -= ypad;
  y1 += ypad;

  cv::Mat img(spec.height, spec.width, CV_8UC3, cv::Scalar(255, 255, 255));
  const int left = 90, right = 30, top = 50, bottom = 70;
  const int pw = spec.width - left - right, ph = spec.height - top - bottom;
  auto px = [&](double x) { return left + static_cast<int>((x - x0) / (x1 - x0) * pw); };
  auto py = [&](double y) { return top + ph - static_cast<int>((y - y0) / (y1 - y0) * ph); };
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  const cv::Scalar black(0, 0, 0), grid(225, 225, 225);

  const double xs = tick_step(x1 - x0), ys = tick_step(y1 - y0);
  for (double t = std::ceil(x0 / xs) * xs; t <= x1 + 1e-12; t += xs) {
    cv::line(img, {px(t), top}, {px(t), top + ph}, grid, 1);
    cv::line(img, {px(t), top + ph}, {px(t), top + ph + 6}, black, 1);
    cv::putText(img, format_tick(t, xs), {px(t) - 18, top + ph + 24}, font, 0.45, black, 1,
                cv::LINE_AA);
  }
  for (double t = std::ceil(y0 / ys) * ys; t <= y1 + 1e-12; t += ys) {
    cv::line(img, {left, py(t)}, {left + pw, py(t)}, grid, 1);
    cv::line(img, {left - 6, py(t)}, {left, py(t)}, black, 1);
    cv::putText(img, format_tick(t, ys), {32, py(t) + 5}, font, 0.45, black, 1, cv::LINE_AA);
  }
  cv::rectangle(img, {left, top}, {left + pw, top + ph}, black, 1);
  cv::putText(img, spec.title, {left, 32}, font, 0.7, black, 2, cv::LINE_AA);
  cv::putText(img, spec.x_label, {left + pw / 2 - 60, spec.height - 20}, font, 0.55, black, 1,
              cv::LINE_AA);
  // Vertical y label: draw horizontally then rotate into place.
  {
    int baseline = 0;
    const cv::Size ts = cv::getTextSize(spec.y_label, font, 0.55, 1, &baseline);
    cv::Mat label(ts.height + baseline + 4, ts.width + 4, CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(label, spec.y_label, {2, ts.height + 2}, font, 0.55, black, 1, cv::LINE_AA);
    cv::Mat rotated;
    cv::rotate(label, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int yy = std::max(0, top + ph / 2 - rotated.rows / 2);
    if (yy + rotated.rows <= img.rows && rotated.cols + 2 <= left)
      rotated.copyTo(img(cv::Rect(2, yy, rotated.cols, rotated.rows)));
  }

  for (const auto& s : spec.series) {
    const cv::Scalar c = bgr(s.rgb);
    const std::size_t n = std::min(s.x.size(), s.y.size());
    for (std::size_t i = 0; i < n; ++i) {
      const cv::Point p(px(s.x[i]), py(s.y[i]));
      if (s.markers)
        cv::circle(img, p, 4, c, cv::FILLED, cv::LINE_AA);
      else if (i > 0)
        cv::line(img, {px(s.x[i - 1]), py(s.y[i - 1])}, p, c, 2, cv::LINE_AA);
    }
  }
  // Legend, bottom right (start-up curves and set-points live at the top).
  int ly = top + ph - 22 * static_cast<int>(spec.series.size()) + 8;
  for (const auto& s : spec.series) {
    const int lx = left + pw - 260;
    if (s.markers)
      cv::circle(img, {lx + 15, ly - 5}, 4, bgr(s.rgb), cv::FILLED, cv::LINE_AA);
    else
      cv::line(img, {lx, ly - 5}, {lx + 30, ly - 5}, bgr(s.rgb), 2, cv::LINE_AA);
    cv::putText(img, s.name, {lx + 38, ly}, font, 0.5, black, 1, cv::LINE_AA);
    ly += 22;
  }
  if (!cv::imwrite(path, img)) throw std::runtime_error("cannot write plot PNG: " + path);
}

}  // namespace weedspray::lab
