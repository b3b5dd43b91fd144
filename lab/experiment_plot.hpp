// SPDX-License-Identifier: Apache-2.0
// Minimal line/scatter plots drawn with OpenCV primitives (axes, ticks, labels, legend) for the
// experiment figures. Lab-only: allocation and exceptions are fine here.
#pragma once

#include <string>
#include <vector>

namespace weedspray::lab {

struct PlotSeries {
  std::string name;
  std::vector<double> x;
  std::vector<double> y;
  int rgb = 0x1f77b4;    // colour 0xRRGGBB
  bool markers = false;  // points with markers instead of a line
};

struct PlotSpec {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<PlotSeries> series;
  int width = 1000;
  int height = 600;
};

// Writes a PNG; throws std::runtime_error naming the file if it cannot be written.
void write_plot_png(const PlotSpec& spec, const std::string& path);

}  // namespace weedspray::lab
