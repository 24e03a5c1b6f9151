// A minimal PNG plotter: linear or log axes with "nice" ticks (steps of 1, 2, 5 x 10^k).
#include "scenelod/eval/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace scenelod::eval {

namespace {

const Rgb8 kBlack{0, 0, 0};
const Rgb8 kGrid{225, 225, 225};
const Rgb8 kAxis{60, 60, 60};

void setPixel(Image& img, int x, int y, Rgb8 c) {
  if (x < 0 || y < 0 || x >= img.width || y >= img.height) return;
  uint8_t* p = img.pixel(x, y);
  p[0] = c.r;
  p[1] = c.g;
  p[2] = c.b;
}

void fillRect(Image& img, int x0, int y0, int x1, int y1, Rgb8 c) {
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) setPixel(img, x, y, c);
}

// Bresenham line, `thick` pixels wide (square brush)
void drawLine(Image& img, int x0, int y0, int x1, int y1, Rgb8 c, int thick = 1) {
  const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
  const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
  int err = dx + dy;
  for (;;) {
    fillRect(img, x0 - (thick - 1) / 2, y0 - (thick - 1) / 2, x0 + thick / 2, y0 + thick / 2, c);
    if (x0 == x1 && y0 == y1) break;
    const int e2 = 2 * err;
    if (e2 >= dy) err += dy, x0 += sx;
    if (e2 <= dx) err += dx, y0 += sy;
  }
}

struct Axis {
  bool log = false;
  double lo = 0.0, hi = 1.0;  // in axis units (log10 when log)
  double map(double v) const { return log ? std::log10(v) : v; }
  bool drawable(double v) const { return std::isfinite(v) && (!log || v > 0.0); }
};

std::string formatTick(double v) {
  char buf[32];
  if (v == 0.0) return "0";
  const double a = std::fabs(v);
  if (a >= 1e6 || a < 1e-3)
    std::snprintf(buf, sizeof buf, "%.0e", v);
  else
    std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// tick values in data units for an axis
std::vector<double> ticks(const Axis& a) {
  std::vector<double> out;
  if (a.log) {
    const int d0 = static_cast<int>(std::floor(a.lo)), d1 = static_cast<int>(std::ceil(a.hi));
    const bool few_decades = d1 - d0 <= 2;
    for (int d = d0; d <= d1; ++d)
      for (double m : {1.0, 2.0, 5.0}) {
        if (m != 1.0 && !few_decades) continue;
        const double v = m * std::pow(10.0, d);
        const double lv = std::log10(v);
        if (lv >= a.lo - 1e-9 && lv <= a.hi + 1e-9) out.push_back(v);
      }
    return out;
  }
  const double span = a.hi - a.lo;
  const double raw = span / 6.0;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  for (double v = std::ceil(a.lo / step) * step; v <= a.hi + 1e-9 * span; v += step)
    out.push_back(std::fabs(v) < 1e-12 * span ? 0.0 : v);
  return out;
}

bool fitAxis(Axis& a, const std::vector<PlotSeries>& series, bool is_x) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& s : series)
    for (size_t i = 0; i < s.x.size(); ++i) {
      const double v = is_x ? s.x[i] : s.y[i];
      const double w = is_x ? s.y[i] : s.x[i];
      if (!a.drawable(v) || !std::isfinite(w)) continue;
      lo = std::min(lo, a.map(v));
      hi = std::max(hi, a.map(v));
    }
  if (!(lo <= hi)) return false;
  if (hi - lo < 1e-12 * std::max(1.0, std::fabs(hi))) {
    const double pad = a.log ? 0.5 : std::max(0.5, std::fabs(hi) * 0.1);
    lo -= pad;
    hi += pad;
  }
  const double margin = 0.05 * (hi - lo);
  a.lo = lo - margin;
  a.hi = hi + margin;
  if (!a.log && lo >= 0.0 && a.lo < 0.0) a.lo = 0.0;  // non-negative data keeps 0 as the floor
  return true;
}

}  // namespace

Rgb8 seriesColor(int index) {
  static const Rgb8 kPalette[8] = {{31, 119, 180}, {214, 39, 40}, {44, 160, 44}, {255, 127, 14},
                                   {148, 103, 189}, {140, 86, 75}, {227, 119, 194}, {23, 190, 207}};
  return kPalette[((index % 8) + 8) % 8];
}

Error drawPlot(const std::vector<PlotSeries>& series, const PlotParams& params, Image& out) {
  if (params.width < 200 || params.height < 150)
    return {Status::kInvalidArgument, "plot: size " + std::to_string(params.width) + "x" +
                                          std::to_string(params.height) + " is below the minimum 200x150"};
  for (const auto& s : series)
    if (s.x.size() != s.y.size())
      return {Status::kInvalidArgument, "plot: series '" + s.name + "' has " + std::to_string(s.x.size()) +
                                            " x values but " + std::to_string(s.y.size()) + " y values"};
  Axis ax, ay;
  ax.log = params.log_x;
  ay.log = params.log_y;
  if (!fitAxis(ax, series, true) || !fitAxis(ay, series, false))
    return {Status::kInvalidArgument, "plot '" + params.title + "': no drawable point (empty series, or only "
                                                               "values <= 0 on a log axis)"};
  out = Image(params.width, params.height);
  // plot area: room on the left for tick labels and the y label, below for ticks and the x label
  const int left = 80, right = params.width - 20, top = params.title.empty() ? 20 : 40,
            bottom = params.height - 50;
  auto px = [&](double v) { return left + static_cast<int>(std::lround((ax.map(v) - ax.lo) / (ax.hi - ax.lo) * (right - left))); };
  auto py = [&](double v) { return bottom - static_cast<int>(std::lround((ay.map(v) - ay.lo) / (ay.hi - ay.lo) * (bottom - top))); };

  for (double t : ticks(ax)) {
    const int x = px(t);
    drawLine(out, x, top, x, bottom, kGrid);
    drawLine(out, x, bottom, x, bottom + 4, kAxis);
    const std::string s = formatTick(t);
    drawText(out, x - textWidth(s) / 2, bottom + 8, s, kBlack);
  }
  for (double t : ticks(ay)) {
    const int y = py(t);
    drawLine(out, left, y, right, y, kGrid);
    drawLine(out, left - 4, y, left, y, kAxis);
    const std::string s = formatTick(t);
    drawText(out, left - 8 - textWidth(s), y - 3, s, kBlack);
  }
  drawLine(out, left, top, left, bottom, kAxis);
  drawLine(out, left, bottom, right, bottom, kAxis);
  drawLine(out, right, top, right, bottom, kAxis);
  drawLine(out, left, top, right, top, kAxis);

  if (!params.title.empty()) drawText(out, (params.width - textWidth(params.title, 2)) / 2, 10, params.title, kBlack, 2);
  if (!params.x_label.empty())
    drawText(out, (left + right - textWidth(params.x_label)) / 2, params.height - 18, params.x_label, kBlack);
  if (!params.y_label.empty())
    drawText(out, 8, (top + bottom + textWidth(params.y_label)) / 2, params.y_label, kBlack, 1, true);

  for (const auto& s : series) {
    bool have_prev = false;
    int prev_x = 0, prev_y = 0;
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!ax.drawable(s.x[i]) || !ay.drawable(s.y[i])) {
        have_prev = false;
        continue;
      }
      const int x = px(s.x[i]), y = py(s.y[i]);
      if (s.lines && have_prev) drawLine(out, prev_x, prev_y, x, y, s.color, 2);
      if (s.markers) fillRect(out, x - 2, y - 2, x + 2, y + 2, s.color);
      have_prev = true;
      prev_x = x;
      prev_y = y;
    }
  }

  // legend in the top-right corner of the plot area
  int named = 0, widest = 0;
  for (const auto& s : series)
    if (!s.name.empty()) ++named, widest = std::max(widest, textWidth(s.name));
  if (named) {
    const int w = widest + 30, h = named * 12 + 6;
    const int x0 = right - w - 6, y0 = top + 6;
    fillRect(out, x0, y0, x0 + w, y0 + h, Rgb8{255, 255, 255});
    drawLine(out, x0, y0, x0 + w, y0, kAxis);
    drawLine(out, x0, y0 + h, x0 + w, y0 + h, kAxis);
    drawLine(out, x0, y0, x0, y0 + h, kAxis);
    drawLine(out, x0 + w, y0, x0 + w, y0 + h, kAxis);
    int row = 0;
    for (const auto& s : series) {
      if (s.name.empty()) continue;
      const int y = y0 + 5 + row * 12;
      drawLine(out, x0 + 5, y + 3, x0 + 20, y + 3, s.color, 2);
      drawText(out, x0 + 25, y, s.name, kBlack);
      ++row;
    }
  }
  return {};
}

Error writePlotPng(const std::string& path, const std::vector<PlotSeries>& series, const PlotParams& params) {
  Image img;
  if (Error e = drawPlot(series, params, img); !e.ok()) {
    e.message = path + ": " + e.message;
    return e;
  }
  return writePng(path, img);
}

}  // namespace scenelod::eval
