#pragma once

#include <string>
#include <vector>

namespace clogscope {

struct PlotSeries {
  std::string title;
  std::vector<double> x, y;
  std::vector<double> y_error;        // optional: error bars
  std::string style = "linespoints";  // gnuplot style: lines, points, linespoints
};

struct PlotSpec {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  int width_px = 960, height_px = 600;
  bool zero_line = false;  // draw y = 0 (residual plots)
};

// Renders the plot to a PNG through gnuplot (Debian's gnuplot-nox), written under a temporary name
// and renamed. Returns false, with the reason in *why, when gnuplot is absent or fails; nothing is
// written then. Plots are a convenience: callers report the reason and go on.
bool PlotToPng(const PlotSpec& spec, const std::string& png_path, std::string* why);

}  // namespace clogscope
