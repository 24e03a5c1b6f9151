// The calibration of the shadow kind's cost scales in frames with views: a synthetic clock whose
// shadow pass costs another share of the shared coefficients than the default scales say, camera
// and cascades moving so that the views' mix varies; the learnt factors, the prediction error
// against the factors fixed at the prior, and the budget adherence (docs/bench/views.md,
// "Calibrated shadow scales", quotes what the first test prints).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "scenelod/selection/replay_runner.h"
#include "selection_fixtures.h"

namespace scenelod::selection {
namespace {

using test::makeCamera;
using test::makeJob;
using test::makeScene;
using test::SyntheticScene;

// The machine: shared coefficients away from the prior, a shadow pass at 0.4x per object, 0.1x per
// pixel and 0.3x per triangle, vertex and line point of them (factors 0.4, 0.4 and 0.6 on the
// default shadow scales 1, 0.25 and 0.5).
CostCoefficients machine() {
  CostCoefficients t = syntheticTrueCost();  // the replays' synthetic clock, with dearer pixels
  t.per_pixel_ms = 4.0e-7;
  t.shadow_object_factor = 0.4;
  t.shadow_pixel_factor = 0.4;
  t.shadow_geometry_factor = 0.6;
  return t;
}

// A cascade: an orthographic light looking down on the ground around (x, z), `side` wide.
View cascade(uint32_t group, float x, float z, float side, uint32_t texels = 2048, float cells = 4.0f) {
  View v;
  v.kind = ViewKind::kShadow;
  v.group = group;
  v.pixels_per_cell = cells;
  v.camera.projection = Projection::kOrthographic;
  v.camera.eye = glm::vec3(x, 200.0f, z);
  v.camera.target = glm::vec3(x, 0.0f, z);
  v.camera.up = glm::vec3(0.0f, 0.0f, -1.0f);
  v.camera.ortho_height = side;
  v.camera.near_plane = 1.0f;
  v.camera.far_plane = 400.0f;
  v.camera.viewport_width_px = v.camera.viewport_height_px = texels;
  return v;
}

View eye(const glm::vec3& at, float yaw) {
  View v;
  v.camera = makeCamera(at);
  v.camera.target = at + glm::vec3(std::sin(yaw), 0.0f, -std::cos(yaw));
  v.kind = ViewKind::kEye;
  return v;
}

struct ClockRun {
  std::vector<CostCoefficients> model;  // the cost model after each frame's report
  double error_after_warmup = 0.0;      // mean |predicted - measured| / measured, frames >= warmup
  double model_error_after_warmup = 0.0;  // ... against the machine's time without the noise
  size_t budget_frames = 0, within_10_percent = 0;
};

// `frames` budget frames of two eyes walking and turning through the scene and two cascades
// around them whose coverage changes, measured by the machine with 5 % noise.
ClockRun runClock(bool learn, int frames, size_t warmup, float budget_ms) {
  const SyntheticScene s = makeScene(10, 2000, 8, 6);
  SelectorConfig cfg;
  cfg.max_object_count = s.centers.size();
  cfg.max_view_groups = 2;
  cfg.calibration.learn_shadow_factors = learn;
  SelectorContext* ctx = createSelectorContext(cfg);
  EXPECT_NE(ctx, nullptr);
  SelectionParams params;
  params.budget_ms = budget_ms;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  ClockRun out;
  double error_sum = 0.0, model_error_sum = 0.0;
  for (int frame = 0; frame < frames; ++frame) {
    const float t = static_cast<float>(frame);
    const glm::vec3 at(20.0f * std::sin(0.013f * t), 0.0f, -30.0f * (0.5f - 0.5f * std::cos(0.011f * t)));
    const float yaw = 0.4f * std::sin(0.017f * t);
    const float near_side = 20.0f + 25.0f * (0.5f + 0.5f * std::sin(0.05f * t));
    const float far_side = 60.0f + 80.0f * (0.5f + 0.5f * std::sin(0.031f * t + 1.0f));
    // the far cascade is drawn every other frame (a staggered update, as engines do for far
    // cascades); the near one's map resolution and X follow a dynamic-resolution controller
    const uint32_t texels = (frame / 3) % 2 ? 1024 : 2048;
    const float cells = 3.0f + 2.0f * std::sin(0.07f * t);
    std::vector<View> views = {eye(at - glm::vec3(0.032f, 0, 0), yaw), eye(at + glm::vec3(0.032f, 0, 0), yaw),
                               cascade(1, at.x, at.z - 0.4f * near_side, near_side, texels, cells)};
    if (frame % 2 == 0) views.push_back(cascade(1, at.x, at.z - 0.4f * far_side, far_side));
    std::vector<int8_t> levels, group_levels(2 * s.centers.size());
    SelectionStats st;
    SelectionJob job = makeJob(s, ctx, nullptr, levels, &st);
    job.params = params;
    job.views = Span<const View>(views.data(), views.size());
    job.group_levels_out = Span<int8_t>(group_levels.data(), group_levels.size());
    EXPECT_TRUE(job.run()) << job.error();
    const double truth = predictFrameMs(machine(), st.features);
    const double measured = truth * (1.0 + noise(rng));
    if (static_cast<size_t>(frame) >= warmup) {
      error_sum += std::fabs(st.predicted_ms - measured) / measured;
      model_error_sum += std::fabs(st.predicted_ms - truth) / truth;
      ++out.budget_frames;
      out.within_10_percent += measured <= 1.1 * budget_ms;
    }
    reportFrameTime(ctx, st.frame, static_cast<float>(measured));
    out.model.push_back(selectorCostModel(ctx));
  }
  out.error_after_warmup = error_sum / static_cast<double>(out.budget_frames);
  out.model_error_after_warmup = model_error_sum / static_cast<double>(out.budget_frames);
  destroySelectorContext(ctx);
  return out;
}

TEST(ShadowCalibration, LearntScalesConvergeAndPredictBetterThanTheDefaults) {
  const int frames = 600;
  const size_t warmup = 60;  // the error and the budget are counted from here
  const ClockRun learnt = runClock(true, frames, warmup, 6.0f), fixed = runClock(false, frames, warmup, 6.0f);
  const CostCoefficients t = machine();
  // the scales (default scale x learnt factor) against the truth, frame by frame
  // object and geometry (most of the shadow pass's cost here); the pixel term is a twentieth of
  // the frame, so its scale moves slower
  const auto within = [&](const CostCoefficients& c, double tol) {
    return std::fabs(c.shadow_object_factor / t.shadow_object_factor - 1.0) <= tol &&
           std::fabs(c.shadow_geometry_factor / t.shadow_geometry_factor - 1.0) <= tol;
  };
  std::printf("frame  object scale  pixel scale  geometry scale   (truth 0.4, 0.1, 0.3)\n");
  for (const int f : {0, 10, 30, 60, 100, 200, 300, 400, 500, frames - 1}) {
    if (f >= frames) continue;
    const CostCoefficients& c = learnt.model[static_cast<size_t>(f)];
    std::printf("%5d  %12.3f  %11.3f  %14.3f\n", f + 1, 1.0 * c.shadow_object_factor, 0.25 * c.shadow_pixel_factor,
                0.5 * c.shadow_geometry_factor);
  }
  int settled = frames;  // the first frame from which object and geometry stay within 35 % of the truth
  for (int f = frames - 1; f >= 0 && within(learnt.model[static_cast<size_t>(f)], 0.35); --f) settled = f;
  std::printf("object and geometry scales within 35 %% of the truth from frame %d on\n", settled + 1);
  std::printf("mean |predicted - measured| / measured after %zu frames: learnt %.4f, fixed defaults %.4f\n", warmup,
              learnt.error_after_warmup, fixed.error_after_warmup);
  std::printf("mean |predicted - noise-free time| / noise-free time: learnt %.4f, fixed defaults %.4f\n",
              learnt.model_error_after_warmup, fixed.model_error_after_warmup);
  std::printf("measured within +10 %% of the budget: learnt %zu/%zu, fixed defaults %zu/%zu\n",
              learnt.within_10_percent, learnt.budget_frames, fixed.within_10_percent, fixed.budget_frames);
  EXPECT_LE(settled, 400);
  // the pixel scale at least a third of the way from the prior (0.25) to the truth (0.1)
  EXPECT_LT(0.25 * learnt.model.back().shadow_pixel_factor, 0.2);
  // the defaults stay where they were, so their frames mispredict
  EXPECT_EQ(fixed.model.back().shadow_object_factor, 1.0);
  EXPECT_EQ(fixed.model.back().shadow_pixel_factor, 1.0);
  EXPECT_EQ(fixed.model.back().shadow_geometry_factor, 1.0);
  EXPECT_LT(learnt.error_after_warmup, 0.05);  // about the 5 % noise (mean |noise| is 4 %)
  EXPECT_LT(learnt.error_after_warmup, 0.8 * fixed.error_after_warmup);
  EXPECT_LT(learnt.model_error_after_warmup, 0.5 * fixed.model_error_after_warmup);
  // the budget holds with views and learnt scales: >= 95 % of the frames within +10 % (the fixed
  // defaults, whose shadow costs are wrong, miss it here)
  EXPECT_GE(learnt.within_10_percent * 100, learnt.budget_frames * 95);
}

TEST(ShadowCalibration, FramesWithoutShadowViewsKeepThePriorFactors) {
  const SyntheticScene s = makeScene(10, 2000, 8, 6);
  SelectorConfig cfg;
  cfg.max_object_count = s.centers.size();
  cfg.max_view_groups = 2;
  cfg.initial_cost.shadow_object_factor = 0.8;
  cfg.initial_cost.shadow_pixel_factor = 1.25;
  cfg.initial_cost.shadow_geometry_factor = 0.5;
  SelectorContext* ctx = createSelectorContext(cfg);
  ASSERT_NE(ctx, nullptr);
  SelectionParams params;
  params.budget_ms = 6.0f;
  for (int frame = 0; frame < 80; ++frame) {
    const glm::vec3 at(0.25f * static_cast<float>(frame), 0.0f, 0.0f);
    const std::vector<View> views = {eye(at - glm::vec3(0.032f, 0, 0), 0.0f), eye(at + glm::vec3(0.032f, 0, 0), 0.0f)};
    std::vector<int8_t> levels, group_levels(s.centers.size());
    SelectionStats st;
    SelectionJob job = makeJob(s, ctx, nullptr, levels, &st);
    job.params = params;
    job.views = Span<const View>(views.data(), views.size());
    job.group_levels_out = Span<int8_t>(group_levels.data(), group_levels.size());
    ASSERT_TRUE(job.run()) << job.error();
    EXPECT_EQ(st.features.shadow_objects, 0.0);
    EXPECT_EQ(st.features.shadow_triangles, 0.0);
    reportFrameTime(ctx, st.frame, static_cast<float>(predictFrameMs(machine(), st.features)));
  }
  const CostCoefficients c = selectorCostModel(ctx);
  EXPECT_NE(c.per_triangle_ms, CostCoefficients().per_triangle_ms);  // the shared ones did learn
  EXPECT_EQ(c.shadow_object_factor, 0.8);
  EXPECT_EQ(c.shadow_pixel_factor, 1.25);
  EXPECT_EQ(c.shadow_geometry_factor, 0.5);
  destroySelectorContext(ctx);
}

TEST(ShadowCalibration, ShadowFeaturesAreTheShadowGroupsAtTheKindsScales) {
  // one frame with an eye group and a cascade group in distance mode: the shadow part of the
  // features counts the shadow group's levels at view_kinds[kShadow]'s scales whatever the factors,
  // and the predicted cost prices it at scale x factor
  const SyntheticScene s = makeScene(10, 500, 8, 6);
  for (const double factor : {1.0, 0.5}) {
    SelectorConfig cfg;
    cfg.max_object_count = s.centers.size();
    cfg.max_view_groups = 2;
    cfg.initial_cost.shadow_geometry_factor = factor;
    cfg.initial_cost.shadow_object_factor = factor;
    cfg.initial_cost.shadow_pixel_factor = factor;
    SelectorContext* ctx = createSelectorContext(cfg);
    ASSERT_NE(ctx, nullptr);
    SelectionParams params;
    params.mode = SelectionMode::kDistance;
    const std::vector<View> views = {eye(glm::vec3(0.0f), 0.0f), cascade(1, 0.0f, -50.0f, 120.0f)};
    std::vector<int8_t> levels, group_levels(2 * s.centers.size());
    SelectionStats st;
    SelectionJob job = makeJob(s, ctx, nullptr, levels, &st);
    job.params = params;
    job.views = Span<const View>(views.data(), views.size());
    job.group_levels_out = Span<int8_t>(group_levels.data(), group_levels.size());
    ASSERT_TRUE(job.run()) << job.error();
    double objects = 0.0, tri = 0.0, shadow_objects = 0.0, shadow_tri = 0.0;
    for (size_t i = 0; i < s.centers.size(); ++i) {
      const uint32_t row0 = s.table.chain_level_offset[s.chains[i]];
      if (group_levels[i] >= 0) {
        objects += 1.0;
        tri += s.table.triangle_count[row0 + static_cast<uint32_t>(group_levels[i])];
      }
      const int8_t sl = group_levels[s.centers.size() + i];
      if (sl >= 0) {
        shadow_objects += 1.0;
        shadow_tri += s.table.triangle_count[row0 + static_cast<uint32_t>(sl)];
      }
    }
    ASSERT_GT(shadow_objects, 0.0);
    EXPECT_DOUBLE_EQ(st.features.objects, objects);
    EXPECT_DOUBLE_EQ(st.features.triangles, tri);
    EXPECT_DOUBLE_EQ(st.features.shadow_objects, shadow_objects);  // object scale 1
    EXPECT_NEAR(st.features.shadow_triangles, 0.5 * shadow_tri, 1e-6 * shadow_tri);  // geometry scale 0.5
    const double want = predictFrameMs(selectorCostModel(ctx), st.features);
    EXPECT_NEAR(st.predicted_ms, want, 1e-4 * want) << factor;
    destroySelectorContext(ctx);
  }
}

}  // namespace
}  // namespace scenelod::selection
