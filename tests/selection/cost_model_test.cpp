#include "scenelod/selection/cost_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
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

// shadow features a fixed multiple of the others (a shadow pass drawing a share of what the eyes draw)
void addShadowShare(CostFeatures& f, double share) {
  f.shadow_objects = share * f.objects;
  f.shadow_triangles = share * f.triangles;
  f.shadow_vertices = share * f.vertices;
  f.shadow_line_points = share * f.line_points;
  f.shadow_pixels = share * f.pixels;
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

// ---- shadow views: the learnt factors on the shadow kind's scales

namespace {

// A machine whose shadow pass costs 0.4x per object, 0.1x per pixel and 0.3x per triangle, vertex
// and line point of the other views' coefficients: with the default shadow scales of
// SelectionParams::view_kinds (object 1, pixel 0.25, geometry 0.5) the factors 0.4, 0.4 and 0.6.
CostCoefficients shadowTruth() {
  CostCoefficients t = truth();
  t.per_pixel_ms = 2.0e-7;  // fill-bound enough for the shadow pixels to matter
  t.shadow_object_factor = 0.4 / 1.0;
  t.shadow_pixel_factor = 0.1 / 0.25;
  t.shadow_geometry_factor = 0.3 / 0.5;
  return t;
}

// A frame's features with a shadow part at the default shadow scales whose mix varies apart from
// the other views' (cascades of changing coverage).
CostFeatures shadowFeatures(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  CostFeatures f = randomFeatures(rng, true);
  const double coverage = 0.2 + 1.2 * u(rng);
  f.shadow_objects = 1.0 * coverage * (200 + 1500 * u(rng));
  f.shadow_triangles = 0.5 * coverage * (1e5 + 2e6 * u(rng));
  f.shadow_vertices = 0.5 * f.shadow_triangles;
  f.shadow_line_points = 0.5 * coverage * (1e3 + 5e4 * u(rng));
  f.shadow_pixels = 0.25 * coverage * (4e6 + 2e7 * u(rng));
  return f;
}

double relativeError(const CostCoefficients& c, const CostFeatures& f, double measured) {
  return std::fabs(predictFrameMs(c, f) - measured) / measured;
}

}  // namespace

TEST(CostModel, PredictionCountsTheShadowPartAtItsFactors) {
  CostCoefficients c = truth();
  c.shadow_object_factor = 0.5;
  c.shadow_pixel_factor = 2.0;
  c.shadow_geometry_factor = 0.25;
  CostFeatures f;
  f.objects = 10;
  f.shadow_objects = 4;
  f.shadow_triangles = 1000;
  f.shadow_vertices = 400;
  f.shadow_line_points = 8;
  f.shadow_pixels = 2e4;
  const double want = 1.2 + 10 * 5e-3 + 0.5 * 4 * 5e-3 + 2.0 * 2e4 * 0.5e-7 +
                      0.25 * (1000 * 2e-6 + 400 * 0.3e-6 + 8 * 4e-6);
  EXPECT_NEAR(predictFrameMs(c, f), want, 1e-12);
  CostFeatures plain = f;
  plain.shadow_objects = plain.shadow_triangles = plain.shadow_vertices = plain.shadow_line_points =
      plain.shadow_pixels = 0.0;
  EXPECT_EQ(predictFrameMs(c, plain), 1.2 + 10 * 5e-3);
}

TEST(CostModel, ShadowFactorsConvergeToTheTruth) {
  // noise-free and with 5 % noise: the factors within 5 % (10 % with noise) of the truth after
  // 300 frames, and the prediction of new frames better than with the factors fixed at the prior
  for (const double noise : {0.0, 0.05}) {
    CalibrationParams fixed_params;
    fixed_params.learn_shadow_factors = false;
    CostCalibrator learnt, fixed(CostCoefficients(), fixed_params);
    std::mt19937 rng(11);
    std::normal_distribution<double> n(0.0, noise);
    for (int i = 0; i < 300; ++i) {
      const CostFeatures f = shadowFeatures(rng);
      const double y = predictFrameMs(shadowTruth(), f) * (1.0 + (noise > 0.0 ? n(rng) : 0.0));
      ASSERT_TRUE(learnt.update(f, y));
      ASSERT_TRUE(fixed.update(f, y));
    }
    const CostCoefficients c = learnt.coefficients(), t = shadowTruth();
    // the pixel term is the smallest part of these frames (a few per cent), so the ridge holds it
    // more: it moves at least half way from the prior (1) to the truth (0.4)
    const double tol = noise > 0.0 ? 0.10 : 0.05;
    EXPECT_NEAR(c.shadow_object_factor, t.shadow_object_factor, tol * t.shadow_object_factor) << noise;
    EXPECT_NEAR(c.shadow_pixel_factor, t.shadow_pixel_factor, 0.3) << noise;
    EXPECT_NEAR(c.shadow_geometry_factor, t.shadow_geometry_factor, tol * t.shadow_geometry_factor) << noise;
    EXPECT_EQ(fixed.coefficients().shadow_object_factor, 1.0);
    EXPECT_EQ(fixed.coefficients().shadow_geometry_factor, 1.0);
    double err_learnt = 0.0, err_fixed = 0.0;
    for (int i = 0; i < 100; ++i) {
      const CostFeatures f = shadowFeatures(rng);
      const double y = predictFrameMs(shadowTruth(), f);
      err_learnt += relativeError(c, f, y) / 100.0;
      err_fixed += relativeError(fixed.coefficients(), f, y) / 100.0;
    }
    std::printf("noise %.2f: prediction error learnt %.4f, fixed %.4f\n", noise, err_learnt, err_fixed);
    EXPECT_LT(err_learnt, noise > 0.0 ? 0.05 : 0.005) << noise;
    EXPECT_LT(err_learnt, 0.5 * err_fixed) << noise << ": " << err_learnt << " against " << err_fixed;
  }
}

TEST(CostModel, FramesWithoutShadowsKeepThePriorExactly) {
  CostCoefficients prior;
  prior.shadow_object_factor = 0.7;
  prior.shadow_pixel_factor = 1.5;
  prior.shadow_geometry_factor = 0.9;
  CalibrationParams fixed_params;
  fixed_params.learn_shadow_factors = false;
  CostCalibrator learnt(prior), fixed(prior, fixed_params);
  std::mt19937 rng(12);
  std::normal_distribution<double> n(0.0, 0.05);
  for (int i = 0; i < 200; ++i) {
    const CostFeatures f = randomFeatures(rng, i % 2 == 0);
    const double y = predictFrameMs(truth(), f) * (1.0 + n(rng));
    learnt.update(f, y);
    fixed.update(f, y);
    const CostCoefficients a = learnt.coefficients(), b = fixed.coefficients();
    ASSERT_EQ(a.shadow_object_factor, 0.7);
    ASSERT_EQ(a.shadow_pixel_factor, 1.5);
    ASSERT_EQ(a.shadow_geometry_factor, 0.9);
    // the shadow rows stay decoupled: the shared coefficients have the bits of a calibration
    // that cannot move the factors at all
    ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "frame " << i;
  }
}

TEST(CostModel, ShadowsInAFixedProportionLeaveTheFactorsAtThePrior) {
  // shadow features a constant multiple of the others': one frame time cannot tell the passes
  // apart; the machine is 1.8x slower than the prior everywhere and its shadows 0.5x the scales,
  // yet the factors stay within 1 % of the prior, and the frame is still predicted
  CostCoefficients t = CostCoefficients();
  t.per_frame_ms *= 1.8;
  t.per_object_ms *= 1.8;
  t.per_triangle_ms *= 1.8;
  t.per_vertex_ms *= 1.8;
  t.per_line_point_ms *= 1.8;
  t.per_pixel_ms *= 1.8;
  t.shadow_object_factor = t.shadow_pixel_factor = t.shadow_geometry_factor = 0.5;
  CostCalibrator cal;
  std::mt19937 rng(13);
  std::normal_distribution<double> n(0.0, 0.05);
  double worst = 0.0;  // the largest distance of a factor from the prior, any frame
  for (int i = 0; i < 500; ++i) {
    CostFeatures f = randomFeatures(rng, false);
    addShadowShare(f, 0.3);
    const double y = predictFrameMs(t, f) * (1.0 + n(rng));
    ASSERT_TRUE(cal.update(f, y));
    const CostCoefficients c = cal.coefficients();
    worst = std::max({worst, std::fabs(c.shadow_object_factor - 1.0), std::fabs(c.shadow_pixel_factor - 1.0),
                      std::fabs(c.shadow_geometry_factor - 1.0)});
  }
  EXPECT_LT(worst, 0.01);
  // and the frames are predicted as by a calibration whose factors cannot move
  CalibrationParams fixed_params;
  fixed_params.learn_shadow_factors = false;
  CostCalibrator fixed(CostCoefficients(), fixed_params);
  std::mt19937 replay(13);
  std::normal_distribution<double> n2(0.0, 0.05);
  for (int i = 0; i < 500; ++i) {
    CostFeatures f = randomFeatures(replay, false);
    addShadowShare(f, 0.3);
    fixed.update(f, predictFrameMs(t, f) * (1.0 + n2(replay)));
  }
  for (int i = 0; i < 50; ++i) {
    CostFeatures f = randomFeatures(rng, false);
    addShadowShare(f, 0.3);
    const double want = predictFrameMs(fixed.coefficients(), f);
    EXPECT_NEAR(predictFrameMs(cal.coefficients(), f), want, 0.01 * want);
  }
}

TEST(CostModel, ShadowFactorsStayFiniteAndInTheirRange) {
  CostCalibrator cal;
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 300; ++i) {
    const CostFeatures f = shadowFeatures(rng);
    // absurd times: shadows a thousand times dearer, or every frame free
    const double y = i < 150 ? predictFrameMs(truth(), f) + 1000.0 * f.shadow_pixels * 1e-7 : 0.0;
    ASSERT_TRUE(cal.update(f, y));
    const CostCoefficients c = cal.coefficients();
    for (const double k : {c.shadow_object_factor, c.shadow_pixel_factor, c.shadow_geometry_factor}) {
      ASSERT_TRUE(std::isfinite(k));
      ASSERT_GE(k, kMinShadowFactor);
      ASSERT_LE(k, kMaxShadowFactor);
    }
    if (i == 149) {
      EXPECT_GT(c.shadow_pixel_factor, 2.0);  // pushed far up, and held at the range's end
    }
  }
  // a bad prior is replaced by 1 or clamped; bad shadow features are refused
  CostCoefficients bad;
  bad.shadow_object_factor = std::nan("");
  bad.shadow_pixel_factor = -2.0;
  bad.shadow_geometry_factor = 1e9;
  CostCalibrator b(bad);
  EXPECT_EQ(b.coefficients().shadow_object_factor, 1.0);
  EXPECT_EQ(b.coefficients().shadow_pixel_factor, 1.0);
  EXPECT_EQ(b.coefficients().shadow_geometry_factor, kMaxShadowFactor);
  CostFeatures f = shadowFeatures(rng);
  f.shadow_pixels = std::nan("");
  EXPECT_FALSE(b.update(f, 5.0));
  f.shadow_pixels = -1.0;
  EXPECT_FALSE(b.update(f, 5.0));
  EXPECT_EQ(b.updateCount(), 0u);
}
