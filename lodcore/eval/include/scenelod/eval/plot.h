#pragma once
// A small line/scatter plotter that draws into an Image (then writePng): axes, ticks, tick labels,
// axis labels, title, legend, optional logarithmic axes. For benchmark and selection reports.
#include <string>
#include <vector>

#include "scenelod/eval/image.h"
#include "scenelod/eval/text.h"
#include "scenelod/lodcore/status.h"

namespace scenelod::eval {

struct PlotSeries {
  std::string name;       // shown in the legend; empty = not listed
  std::vector<double> x;  // same length as y; points that are not finite (or <= 0 on a log axis) are skipped
  std::vector<double> y;
  Rgb8 color;
  bool lines = true;    // join consecutive points
  bool markers = true;  // a small square at each point
};

struct PlotParams {
  std::string title;
  std::string x_label;
  std::string y_label;
  int width = 800;
  int height = 500;
  bool log_x = false;
  bool log_y = false;
};

// A distinct colour for series `index` (a fixed palette of 8, repeating).
Rgb8 seriesColor(int index);

// Draws the series into `out` (white background). The axis ranges cover every drawable point with
// a small margin. Errors: width < 200 or height < 150, a series whose x and y differ in length, or
// no drawable point at all. Cost: O(points + pixels); allocates the image.
Error drawPlot(const std::vector<PlotSeries>& series, const PlotParams& params, Image& out);

// drawPlot then writePng to `path`.
Error writePlotPng(const std::string& path, const std::vector<PlotSeries>& series, const PlotParams& params);

}  // namespace scenelod::eval
