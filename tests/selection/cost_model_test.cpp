#include "scenelod/selection/cost_model.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

using namespace scenelod::selection;

namespace {

CostCoefficients truth() {
  CostCoefficients t;
  t.per_frame_ms = 1.2;
  t.per_object_ms = 5.0e-3;
  t.per_triangle_ms = 2.0e-6;
  t.per_vertex_ms = 0.3e-6;
  t.per_line_point_ms = 4.0e-6;
  t.per_pixel_ms = 0.5e-7;
  return t;
}

CostFeatures randomFeatures(std::mt19937& rng, bool collinear) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  CostFeatures f;
  f.objects = 100 + 2000 * u(rng);
  f.triangles = 1e5 + 3e6 * u(rng);
  f.vertices = collinear ? 0.5 * f.triangles : 5e4 + 2e6 * u(rng);
  f.line_points = 1e3 + 1e5 * u(rng);
  f.pixels = 1e5 + 4e6 * u(rng);
  return f;
}

}  // namespace

TEST(CostModel, PredictionIsTheLinearSum) {
  const CostCoefficients t = truth();
  CostFeatures f;
  f.objects = 10;
  f.triangles = 1000;
  f.vertices = 500;
  f.line_points = 20;
  f.pixels = 1e4;
  EXPECT_DOUBLE_EQ(predictFrameMs(t, f), 1.2 + 10 * 5e-3 + 1000 * 2e-6 + 500 * 0.3e-6 + 20 * 4e-6 + 1e4 * 0.5e-7);
}

TEST(CostModel, RecoversTrueCoefficientsFromNoiseFreeFrames) {
  CostCalibrator cal;  // starts from the default prior, far from the truth
  std::mt19937 rng(1);
  for (int i = 0; i < 200; ++i) {
    const CostFeatures f = randomFeatures(rng, false);
    ASSERT_TRUE(cal.update(f, predictFrameMs(truth(), f)));
  }
  const CostCoefficients c = cal.coefficients(), t = truth();
  EXPECT_NEAR(c.per_frame_ms, t.per_frame_ms, 0.02 * t.per_frame_ms);
  EXPECT_NEAR(c.per_object_ms, t.per_object_ms, 0.02 * t.per_object_ms);
  EXPECT_NEAR(c.per_triangle_ms, t.per_triangle_ms, 0.02 * t.per_triangle_ms);
  EXPECT_NEAR(c.per_vertex_ms, t.per_vertex_ms, 0.05 * t.per_vertex_ms);
  // edges and points are about 1 % of these frames, so the ridge holds them less tightly
  EXPECT_NEAR(c.per_line_point_ms, t.per_line_point_ms, 0.10 * t.per_line_point_ms);
  EXPECT_NEAR(c.per_pixel_ms, t.per_pixel_ms, 0.02 * t.per_pixel_ms);
}

TEST(CostModel, CollinearTrianglesAndVerticesStillPredictWell) {
  CostCalibrator cal;
  std::mt19937 rng(2);
  for (int i = 0; i < 300; ++i) {
    const CostFeatures f = randomFeatures(rng, true);
    cal.update(f, predictFrameMs(truth(), f));
  }
  const CostCoefficients c = cal.coefficients();
  EXPECT_GE(c.per_triangle_ms, 0.0);
  EXPECT_GE(c.per_vertex_ms, 0.0);
  // the split between the two is not identifiable, their combination is
  EXPECT_NEAR(c.per_triangle_ms + 0.5 * c.per_vertex_ms, truth().per_triangle_ms + 0.5 * truth().per_vertex_ms,
              0.03 * truth().per_triangle_ms);
  for (int i = 0; i < 50; ++i) {
    const CostFeatures f = randomFeatures(rng, true);
    const double want = predictFrameMs(truth(), f);
    EXPECT_NEAR(predictFrameMs(c, f), want, 0.02 * want);
  }
}

TEST(CostModel, CoefficientsStayNonNegative) {
  CostCoefficients t = truth();
  t.per_line_point_ms = 0.0;
  t.per_pixel_ms = 0.0;
  CostCalibrator cal;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (int i = 0; i < 400; ++i) {
    const CostFeatures f = randomFeatures(rng, false);
    const double y = predictFrameMs(t, f);
    cal.update(f, y * (1.0 + noise(rng)));
    const CostCoefficients c = cal.coefficients();
    ASSERT_GE(c.per_frame_ms, 0.0);
    ASSERT_GE(c.per_object_ms, 0.0);
    ASSERT_GE(c.per_triangle_ms, 0.0);
    ASSERT_GE(c.per_vertex_ms, 0.0);
    ASSERT_GE(c.per_line_point_ms, 0.0);
    ASSERT_GE(c.per_pixel_ms, 0.0);
  }
}

TEST(CostModel, ATermTheMachineDoesNotPayGoesToZero) {
  CostCoefficients t = truth();
  t.per_pixel_ms = 0.0;
  CostCalibrator cal;
  std::mt19937 rng(6);
  for (int i = 0; i < 300; ++i) {
    const CostFeatures f = randomFeatures(rng, false);
    cal.update(f, predictFrameMs(t, f));
  }
  EXPECT_GE(cal.coefficients().per_pixel_ms, 0.0);
  EXPECT_LT(cal.coefficients().per_pixel_ms, 0.05 * CostCoefficients().per_pixel_ms);
}

TEST(CostModel, ForgettingTracksAChangedMachine) {
  CostCalibrator cal;
  std::mt19937 rng(4);
  for (int i = 0; i < 100; ++i) {
    const CostFeatures f = randomFeatures(rng, false);
    cal.update(f, predictFrameMs(truth(), f));
  }
  CostCoefficients slower = truth();
  slower.per_triangle_ms *= 2.0;
  slower.per_pixel_ms *= 3.0;
  for (int i = 0; i < 80; ++i) {
    const CostFeatures f = randomFeatures(rng, false);
    cal.update(f, predictFrameMs(slower, f));
  }
  for (int i = 0; i < 20; ++i) {
    const CostFeatures f = randomFeatures(rng, false);
    const double want = predictFrameMs(slower, f);
    EXPECT_NEAR(predictFrameMs(cal.coefficients(), f), want, 0.02 * want);
  }
}

TEST(CostModel, BadMeasurementsAreIgnored) {
  CostCalibrator cal;
  std::mt19937 rng(5);
  const CostFeatures f = randomFeatures(rng, false);
  EXPECT_FALSE(cal.update(f, std::nan("")));
  EXPECT_FALSE(cal.update(f, -1.0));
  EXPECT_FALSE(cal.update(f, INFINITY));
  CostFeatures bad = f;
  bad.triangles = -5.0;
  EXPECT_FALSE(cal.update(bad, 3.0));
  EXPECT_EQ(cal.updateCount(), 0u);
  EXPECT_EQ(cal.coefficients().per_triangle_ms, CostCoefficients().per_triangle_ms);
}
