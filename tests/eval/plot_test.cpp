#include "scenelod/eval/plot.h"

#include <gtest/gtest.h>

#include "test_support.h"

namespace scenelod::eval {
namespace {

size_t countColor(const Image& img, Rgb8 c) {
  size_t n = 0;
  for (size_t i = 0; i < img.rgb.size(); i += 3) n += img.rgb[i] == c.r && img.rgb[i + 1] == c.g && img.rgb[i + 2] == c.b;
  return n;
}

TEST(Plot, DrawsSeriesAxesAndLegend) {
  PlotSeries a{"ours", {1, 10, 100}, {0.5, 0.2, 0.1}, seriesColor(0)};
  PlotSeries b{"meshopt", {1, 10, 100}, {0.6, 0.3, 0.2}, seriesColor(1)};
  PlotParams p;
  p.title = "Error vs triangles";
  p.x_label = "triangles";
  p.y_label = "hausdorff %";
  p.log_x = true;
  Image img;
  ASSERT_TRUE(drawPlot({a, b}, p, img).ok());
  EXPECT_EQ(img.width, 800);
  // both series leave ink in their own colour: lines, markers and the legend swatch
  EXPECT_GT(countColor(img, a.color), 200u);
  EXPECT_GT(countColor(img, b.color), 200u);
  EXPECT_GT(countColor(img, Rgb8{0, 0, 0}), 300u);  // text
  const std::string path = test::scratchDir() + "/plot.png";
  EXPECT_TRUE(writePlotPng(path, {a, b}, p).ok());
  EXPECT_TRUE(test::fileExists(path));
}

// The marker of a point sits where the axes put it: the lowest y at the bottom, the highest at the top.
TEST(Plot, PointsLandInOrder) {
  PlotSeries s{"", {0, 1}, {0, 1}, Rgb8{255, 0, 0}, false, true};
  PlotParams p;
  Image img;
  ASSERT_TRUE(drawPlot({s}, p, img).ok());
  int min_x = img.width, max_x = -1, min_y = img.height, max_y = -1;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const uint8_t* c = img.pixel(x, y);
      if (c[0] == 255 && c[1] == 0 && c[2] == 0) {
        min_x = std::min(min_x, x), max_x = std::max(max_x, x);
        min_y = std::min(min_y, y), max_y = std::max(max_y, y);
      }
    }
  ASSERT_GE(max_x, 0);
  EXPECT_GT(max_x - min_x, 500);  // two markers far apart: one lower-left, one upper-right
  EXPECT_GT(max_y - min_y, 300);
  const uint8_t* lower_left = img.pixel(min_x + 2, max_y - 2);
  EXPECT_EQ(lower_left[0], 255);
}

TEST(Plot, BadInputGivesClearErrors) {
  Image img;
  PlotParams p;
  EXPECT_EQ(drawPlot({}, p, img).status, Status::kInvalidArgument);
  PlotSeries bad{"bad", {1, 2}, {1}, seriesColor(0)};
  const Error e = drawPlot({bad}, p, img);
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_NE(e.message.find("bad"), std::string::npos);
  PlotSeries neg{"neg", {-1, 0}, {1, 2}, seriesColor(0)};
  p.log_x = true;
  EXPECT_EQ(drawPlot({neg}, p, img).status, Status::kInvalidArgument);
  p.log_x = false;
  p.width = 10;
  EXPECT_EQ(drawPlot({neg}, p, img).status, Status::kInvalidArgument);
}

TEST(Text, DrawsInkInsideItsBox) {
  Image img(100, 20);
  drawText(img, 2, 2, "Ab1%", Rgb8{0, 0, 0});
  size_t ink = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (img.pixel(x, y)[0] == 0) {
        ++ink;
        EXPECT_GE(x, 2);
        EXPECT_LT(x, 2 + textWidth("Ab1%"));
        EXPECT_GE(y, 2);
        EXPECT_LT(y, 2 + kTextHeight);
      }
  EXPECT_GT(ink, 30u);
}

}  // namespace
}  // namespace scenelod::eval
