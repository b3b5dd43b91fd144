// SPDX-License-Identifier: Apache-2.0
#include "vision/overlay.hpp"

#include <png.h>

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "vision/weed_source.hpp"

namespace weedspray::vision {
namespace {

cv::Scalar scalar(OverlayColour c) {
  return {static_cast<double>(c.b), static_cast<double>(c.g), static_cast<double>(c.r)};
}

// The frame as a packed BGR image of its own size (a copy: the overlay is drawn into it).
cv::Mat frame_as_bgr(const ImageView& frame) {
  auto* data = const_cast<std::uint8_t*>(frame.data);  // read only: OpenCV's headers are not const
  cv::Mat bgr;
  switch (frame.format) {
    case PixelFormat::kBgr24:
      cv::Mat(frame.height, frame.width, CV_8UC3, data, frame.stride).copyTo(bgr);
      break;
    case PixelFormat::kRgb24:
      cv::cvtColor(cv::Mat(frame.height, frame.width, CV_8UC3, data, frame.stride), bgr,
                   cv::COLOR_RGB2BGR);
      break;
    case PixelFormat::kYuyv:
      cv::cvtColor(cv::Mat(frame.height, frame.width, CV_8UC2, data, frame.stride), bgr,
                   cv::COLOR_YUV2BGR_YUYV);
      break;
    case PixelFormat::kGrey:
      cv::cvtColor(cv::Mat(frame.height, frame.width, CV_8UC1, data, frame.stride), bgr,
                   cv::COLOR_GRAY2BGR);
      break;
  }
  return bgr;
}

void check_inputs(const ImageView& frame, const ImageView& classes, const PixelRect& region,
                  const OverlayZones& zones) {
  if (frame.data == nullptr || frame.width < 1 || frame.height < 1)
    throw std::invalid_argument("overlay: empty frame");
  if (classes.data == nullptr || classes.width < 1 || classes.height < 1 ||
      classes.stride < static_cast<std::size_t>(classes.width))
    throw std::invalid_argument("overlay: empty class map");
  if (region.x < 0 || region.y < 0 || region.width < 1 || region.height < 1 ||
      region.x + region.width > frame.width || region.y + region.height > frame.height)
    throw std::invalid_argument("overlay: region outside the frame");
  if (zones.rows < 1 || zones.cols < 1 || zones.cols > region.width || zones.rows > region.height)
    throw std::invalid_argument("overlay: zone grid does not fit the region");
  if (zones.density.size() < static_cast<std::size_t>(zones.rows * zones.cols))
    throw std::invalid_argument("overlay: fewer densities than zones");
  if (!zones.duty_pct.empty() && zones.duty_pct.size() < static_cast<std::size_t>(zones.cols))
    throw std::invalid_argument("overlay: fewer duties than zone columns");
}

// White text with a dark outline: readable on soil, plants and the overlay colours alike.
void label(cv::Mat& image, const std::string& text, cv::Point at, double scale, int thickness) {
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), thickness + 2,
              cv::LINE_AA);
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(255, 255, 255),
              thickness, cv::LINE_AA);
}

}  // namespace

BgrImage draw_overlay(const ImageView& frame, const ImageView& classes, const PixelRect& region,
                      const OverlayZones& zones) {
  check_inputs(frame, classes, region, zones);
  cv::Mat overlay = frame_as_bgr(frame);
  const cv::Mat class_view(classes.height, classes.width, CV_8UC1,
                           const_cast<std::uint8_t*>(classes.data), classes.stride);
  const cv::Size region_size(region.width, region.height);
  cv::Mat region_classes;
  if (class_view.size() == region_size) {
    region_classes = class_view;
  } else {  // dnn: the network's resolution
    cv::resize(class_view, region_classes, region_size, 0, 0, cv::INTER_NEAREST);
  }
  cv::Mat roi = overlay(cv::Rect(region.x, region.y, region.width, region.height));
  roi = roi * 0.6;
  roi.setTo(scalar(kOverlayCrop), region_classes == kClassCrop);
  roi.setTo(scalar(kOverlayWeed), region_classes == kClassWeed);

  const double font_scale = std::max(0.35, region.width / 900.0);
  const int thickness = std::max(1, region.width / 500);
  const int line_height = static_cast<int>(26 * font_scale) + 2 * thickness;
  for (int row = 0; row < zones.rows; ++row) {
    for (int col = 0; col < zones.cols; ++col) {
      const cv::Point top_left(region.x + col * region.width / zones.cols,
                               region.y + row * region.height / zones.rows);
      const cv::Point bottom_right(region.x + (col + 1) * region.width / zones.cols - 1,
                                   region.y + (row + 1) * region.height / zones.rows - 1);
      cv::rectangle(overlay, top_left, bottom_right, scalar(kOverlayGrid), thickness);
      char text[32];
      std::snprintf(text, sizeof text, "%.1f%%",
                    100.0 * zones.density[static_cast<std::size_t>(row * zones.cols + col)]);
      cv::Point at(top_left.x + 3 * thickness, top_left.y + line_height);
      label(overlay, text, at, font_scale, thickness);
      if (zones.duty_pct.empty()) continue;
      std::snprintf(text, sizeof text, "duty %.0f%%",
                    zones.duty_pct[static_cast<std::size_t>(col)]);
      at.y += line_height;
      label(overlay, text, at, font_scale, thickness);
    }
  }
  BgrImage out;
  out.width = overlay.cols;
  out.height = overlay.rows;
  out.pixels.assign(overlay.datastart, overlay.dataend);  // continuous: made by copy/cvtColor
  return out;
}

// libpng's simplified API: no setjmp error handling in C++ code, and the fast filter and
// compression settings a live view wants (PNG_IMAGE_FLAG_FAST).
std::vector<std::uint8_t> encode_png(const BgrImage& image) {
  png_image description{};
  description.version = PNG_IMAGE_VERSION;
  description.width = static_cast<png_uint_32>(image.width);
  description.height = static_cast<png_uint_32>(image.height);
  description.format = PNG_FORMAT_BGR;
  description.flags = PNG_IMAGE_FLAG_FAST;
  const auto stride = static_cast<png_int_32>(image.width * 3);
  png_alloc_size_t size = 0;
  if (image.width < 1 || image.height < 1 ||
      image.pixels.size() < static_cast<std::size_t>(image.width) * image.height * 3 ||
      png_image_write_to_memory(&description, nullptr, &size, 0, image.pixels.data(), stride,
                                nullptr) == 0)
    throw std::runtime_error(std::string("PNG encoding failed: ") + description.message);
  std::vector<std::uint8_t> png(size);
  if (png_image_write_to_memory(&description, png.data(), &size, 0, image.pixels.data(), stride,
                                nullptr) == 0)
    throw std::runtime_error(std::string("PNG encoding failed: ") + description.message);
  png.resize(size);
  return png;
}

}  // namespace weedspray::vision
