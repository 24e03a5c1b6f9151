// Frames with several views: groups (stereo eyes), shadow cascades under the primary view's
// detail, per-view bias, forced levels, one budget across views, and the errors of bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "selection_fixtures.h"

namespace scenelod::selection {
namespace {

using test::makeCamera;
using test::makeJob;
using test::makeScene;
using test::SyntheticScene;

SelectorContext* viewContext(size_t objects, size_t groups) {
  SelectorConfig cfg;
  cfg.max_object_count = objects;
  cfg.max_view_groups = groups;
  return createSelectorContext(cfg);
}

View eyeView(float dx, uint32_t group = 0) {
  View v;
  v.camera = makeCamera(glm::vec3(dx, 0.0f, 0.0f));
  v.kind = ViewKind::kEye;
  v.group = group;
  return v;
}

View primaryView(const glm::vec3& eye = glm::vec3(0.0f)) {
  View v;
  v.camera = makeCamera(eye);
  return v;
}

// An orthographic light looking straight down on the scene box of makeScene (extent 100).
View shadowView(uint32_t group, float x = 1.0f, float ortho_height = 120.0f) {
  View v;
  v.kind = ViewKind::kShadow;
  v.group = group;
  v.pixels_per_cell = x;
  v.camera.projection = Projection::kOrthographic;
  v.camera.eye = glm::vec3(0.0f, 200.0f, -50.0f);
  v.camera.target = glm::vec3(0.0f, 0.0f, -50.0f);
  v.camera.up = glm::vec3(0.0f, 0.0f, -1.0f);
  v.camera.ortho_height = ortho_height;
  v.camera.near_plane = 1.0f;
  v.camera.far_plane = 400.0f;
  v.camera.viewport_width_px = 2048;
  v.camera.viewport_height_px = 2048;
  return v;
}

struct ViewRun {
  std::vector<int8_t> levels, group_levels;
  SelectionStats stats;
};

// Runs one frame of `views` over the scene; groups = the group count the views make.
bool runViews(const SyntheticScene& s, SelectorContext* ctx, const std::vector<View>& views, size_t groups,
              const SelectionParams& params, ViewRun* out, const std::vector<int8_t>* forced = nullptr) {
  SelectionJob job = makeJob(s, ctx, nullptr, out->levels, &out->stats);
  job.params = params;
  job.views = Span<const View>(views.data(), views.size());
  out->group_levels.assign(groups * s.centers.size(), 0);
  job.group_levels_out = Span<int8_t>(out->group_levels.data(), out->group_levels.size());
  if (forced) job.forced_levels = Span<const int8_t>(forced->data(), forced->size());
  return job.run();
}

SelectionParams distanceParams() {
  SelectionParams p;
  p.mode = SelectionMode::kDistance;
  return p;
}

SelectionParams budgetParams(float budget_ms) {
  SelectionParams p;
  p.budget_ms = budget_ms;
  p.calibrate = false;
  return p;
}

TEST(Views, TheEyesOfAGroupShareTheLevelTheNearerEyeNeeds) {
  const SyntheticScene s = makeScene(3, 400, 6, 6);
  SelectorContext* ctx = viewContext(s.centers.size(), 1);
  const std::vector<View> eyes = {eyeView(-3.0f), eyeView(3.0f)};
  ViewRun both, left, right;
  ASSERT_TRUE(runViews(s, ctx, eyes, 1, distanceParams(), &both));
  EXPECT_EQ(both.stats.group_count, 1u);
  resetSelectorHistory(ctx);
  ASSERT_TRUE(runViews(s, ctx, {eyes[0]}, 1, distanceParams(), &left));
  resetSelectorHistory(ctx);
  ASSERT_TRUE(runViews(s, ctx, {eyes[1]}, 1, distanceParams(), &right));
  size_t seen_by_one = 0;
  for (size_t i = 0; i < s.centers.size(); ++i) {
    const int l = left.levels[i], r = right.levels[i];
    // the union of the frusta, the finer of the two eyes' levels
    const int expect = l < 0 ? r : r < 0 ? l : std::min(l, r);
    EXPECT_EQ(both.levels[i], expect) << i;
    EXPECT_EQ(both.group_levels[i], both.levels[i]);
    seen_by_one += (l < 0) != (r < 0);
  }
  EXPECT_GT(seen_by_one, 0u);  // the frusta differ, so the union is tested
  destroySelectorContext(ctx);
}

TEST(Views, AShadowIsNeverFinerThanThePrimaryViewWhereThatSeesTheObject) {
  const SyntheticScene s = makeScene(5, 600, 8, 6);
  SelectorContext* ctx = viewContext(s.centers.size(), 2);
  // a shadow at X = 0.25 would want finer levels than the camera for most objects
  const std::vector<View> views = {primaryView(), shadowView(7, 0.25f)};
  for (const SelectionParams& params : {distanceParams(), budgetParams(40.0f), budgetParams(4.0f)}) {
    resetSelectorHistory(ctx);
    ViewRun run;
    for (int frame = 0; frame < 3; ++frame) ASSERT_TRUE(runViews(s, ctx, views, 2, params, &run));
    size_t both = 0;
    for (size_t i = 0; i < s.centers.size(); ++i) {
      const int p = run.group_levels[i], sh = run.group_levels[s.centers.size() + i];
      EXPECT_EQ(run.levels[i], p);
      const bool primary_sees = sphereInFrustum(computeFrustum(views[0].camera), s.centers[i], s.radii[i]);
      if (!primary_sees) continue;
      if (p < 0) {
        EXPECT_EQ(sh, -1) << i;
      }
      if (p >= 0 && sh >= 0) {
        EXPECT_GE(sh, p) << i;
        ++both;
      }
    }
    EXPECT_GT(both, 50u);
  }
  destroySelectorContext(ctx);
}

TEST(Views, AnObjectOnlyTheShadowSeesIsSelectedForIt) {
  SyntheticScene s = makeScene(9, 50, 4, 5);
  // behind the camera (z > 0) but under the light
  s.centers[0] = glm::vec3(10.0f, 0.0f, 8.0f);
  SelectorContext* ctx = viewContext(s.centers.size(), 2);
  const std::vector<View> views = {primaryView(), shadowView(1, 4.0f)};
  for (const SelectionParams& params : {distanceParams(), budgetParams(100.0f)}) {
    resetSelectorHistory(ctx);
    ViewRun run;
    ASSERT_TRUE(runViews(s, ctx, views, 2, params, &run));
    EXPECT_EQ(run.levels[0], -1);
    EXPECT_GE(run.group_levels[s.centers.size()], 0);
  }
  destroySelectorContext(ctx);
}

TEST(Views, AnObjectOutsideEveryViewCostsNothing) {
  SyntheticScene s = makeScene(2, 20, 2, 4);
  s.centers[3] = glm::vec3(0.0f, 5000.0f, 5000.0f);
  SelectorContext* ctx = viewContext(s.centers.size(), 2);
  std::vector<float> cost(s.centers.size());
  std::vector<int8_t> levels, group_levels(2 * s.centers.size());
  SelectionStats st;
  SelectionJob job = makeJob(s, ctx, nullptr, levels, &st);
  const std::vector<View> views = {primaryView(), shadowView(1)};
  job.views = Span<const View>(views.data(), views.size());
  job.group_levels_out = Span<int8_t>(group_levels.data(), group_levels.size());
  job.cost_ms_out = Span<float>(cost.data(), cost.size());
  job.params = budgetParams(50.0f);
  ASSERT_TRUE(job.run());
  EXPECT_EQ(group_levels[3], -1);
  EXPECT_EQ(group_levels[s.centers.size() + 3], -1);
  EXPECT_EQ(cost[3], 0.0f);
  EXPECT_GE(st.culled_count, 1u);
  double sum = 0.0;
  for (float c : cost) sum += c;
  EXPECT_NEAR(st.predicted_ms, selectorCostModel(ctx).per_frame_ms + sum, 1e-3 * st.predicted_ms);
  destroySelectorContext(ctx);
}

TEST(Views, ABiasActsAsAMultipleOfX) {
  const SyntheticScene s = makeScene(4, 300, 6, 6);
  SelectorContext* ctx = viewContext(s.centers.size(), 1);
  View biased = primaryView(), doubled = primaryView();
  biased.lod_bias = 2.0f;
  doubled.pixels_per_cell = 2.0f;
  ViewRun a, b, plain;
  ASSERT_TRUE(runViews(s, ctx, {biased}, 1, distanceParams(), &a));
  resetSelectorHistory(ctx);
  ASSERT_TRUE(runViews(s, ctx, {doubled}, 1, distanceParams(), &b));
  resetSelectorHistory(ctx);
  ASSERT_TRUE(runViews(s, ctx, {primaryView()}, 1, distanceParams(), &plain));
  EXPECT_EQ(a.levels, b.levels);
  size_t coarser = 0;
  for (size_t i = 0; i < s.centers.size(); ++i) {
    if (plain.levels[i] < 0) continue;
    EXPECT_GE(a.levels[i], plain.levels[i]);
    coarser += a.levels[i] > plain.levels[i];
  }
  EXPECT_GT(coarser, 0u);
  destroySelectorContext(ctx);
}

TEST(Views, ForcedLevelsAreDrawnInEveryGroupThatSeesTheObject) {
  SyntheticScene s = makeScene(6, 200, 5, 5);
  SelectorContext* ctx = viewContext(s.centers.size(), 2);
  std::vector<int8_t> forced(s.centers.size(), -1);
  for (size_t i = 0; i < forced.size(); i += 7) forced[i] = static_cast<int8_t>(i % 5);
  const std::vector<View> views = {primaryView(), shadowView(1, 4.0f)};
  // a budget far too small: forced objects are drawn all the same
  for (const SelectionParams& params : {distanceParams(), budgetParams(0.01f)}) {
    resetSelectorHistory(ctx);
    ViewRun run;
    ASSERT_TRUE(runViews(s, ctx, views, 2, params, &run, &forced));
    for (size_t i = 0; i < forced.size(); ++i) {
      if (forced[i] < 0) continue;
      for (size_t g = 0; g < 2; ++g) {
        const int l = run.group_levels[g * forced.size() + i];
        const bool seen = sphereInFrustum(computeFrustum(views[g].camera), s.centers[i], s.radii[i]);
        EXPECT_EQ(l, seen ? forced[i] : -1) << i << " group " << g;
      }
    }
  }
  // forced levels on a single-camera job
  const Camera cam = makeCamera();
  std::vector<int8_t> levels;
  SelectionJob job = makeJob(s, ctx, &cam, levels, nullptr);
  job.params = distanceParams();
  job.forced_levels = Span<const int8_t>(forced.data(), forced.size());
  ASSERT_TRUE(job.run());
  for (size_t i = 0; i < forced.size(); ++i)
    if (forced[i] >= 0 && levels[i] >= 0) {
      EXPECT_EQ(levels[i], forced[i]);
    }
  destroySelectorContext(ctx);
}

TEST(Views, OnePrimaryViewSelectsAsTheCameraPathInDistanceMode) {
  const SyntheticScene s = makeScene(8, 500, 6, 6, 100.0f, true);
  SelectorContext* ctx = viewContext(s.centers.size(), 1);
  SelectorContext* plain_ctx = test::makeContext(s.centers.size());
  std::vector<int8_t> levels;
  for (int frame = 0; frame < 4; ++frame) {
    Camera cam = makeCamera(glm::vec3(0.5f * frame, 0.0f, -3.0f * frame));
    View v;
    v.camera = cam;
    ViewRun run;
    ASSERT_TRUE(runViews(s, ctx, {v}, 1, distanceParams(), &run));
    SelectionJob job = makeJob(s, plain_ctx, &cam, levels, nullptr);
    job.params = distanceParams();
    ASSERT_TRUE(job.run());
    EXPECT_EQ(run.levels, levels) << frame;
  }
  destroySelectorContext(plain_ctx);
  destroySelectorContext(ctx);
}

TEST(Views, OnePrimaryViewUnderAnAmpleBudgetDrawsWhatTheCameraPathDraws) {
  const SyntheticScene s = makeScene(12, 400, 6, 6);
  SelectorContext* ctx = viewContext(s.centers.size(), 1);
  SelectorContext* plain_ctx = test::makeContext(s.centers.size());
  const Camera cam = makeCamera();
  View v;
  v.camera = cam;
  ViewRun run;
  ASSERT_TRUE(runViews(s, ctx, {v}, 1, budgetParams(1e6f), &run));
  std::vector<int8_t> levels;
  SelectionStats st;
  SelectionJob job = makeJob(s, plain_ctx, &cam, levels, &st);
  job.params = budgetParams(1e6f);
  ASSERT_TRUE(job.run());
  EXPECT_EQ(run.levels, levels);
  EXPECT_NEAR(run.stats.total_benefit, st.total_benefit, 1e-6 * st.total_benefit);
  destroySelectorContext(plain_ctx);
  destroySelectorContext(ctx);
}

TEST(Views, TheBudgetHoldsAcrossViewsAlongAPath) {
  const SyntheticScene s = makeScene(10, 2000, 8, 6);
  SelectorContext* ctx = viewContext(s.centers.size(), 2);
  size_t frames = 0, flagged = 0;
  double lowest = 1e300;
  for (int frame = 0; frame < 40; ++frame) {
    const float dx = 0.25f * static_cast<float>(frame);
    std::vector<View> views = {eyeView(dx - 0.03f), eyeView(dx + 0.03f), shadowView(1, 4.0f, 60.0f),
                               shadowView(1, 4.0f, 120.0f)};
    ViewRun run;
    ASSERT_TRUE(runViews(s, ctx, views, 2, budgetParams(6.0f), &run));
    ++frames;
    if (run.stats.flags & kFlagOverBudget) {
      ++flagged;
      continue;
    }
    EXPECT_LE(run.stats.predicted_ms, 6.0 * (1.0 + 1e-5)) << frame;
    lowest = std::min(lowest, run.stats.predicted_ms);
    EXPECT_GT(run.stats.dropped_count + run.stats.drawn_count, 0u);
  }
  EXPECT_EQ(flagged, 0u);
  EXPECT_GT(lowest, 6.0 * 0.8);  // the budget is used, not left idle
  destroySelectorContext(ctx);
}

// An orthographic view looking down -z (primary) or -y (shadow) over the box [-10, 10]^3.
View orthoView(ViewKind kind, uint32_t group, bool from_above) {
  View v;
  v.kind = kind;
  v.group = group;
  v.camera.projection = Projection::kOrthographic;
  v.camera.eye = from_above ? glm::vec3(0.0f, 50.0f, 0.0f) : glm::vec3(0.0f, 0.0f, 50.0f);
  v.camera.target = glm::vec3(0.0f);
  v.camera.up = from_above ? glm::vec3(0.0f, 0.0f, -1.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
  v.camera.ortho_height = 20.0f;
  v.camera.near_plane = 1.0f;
  v.camera.far_plane = 100.0f;
  v.camera.viewport_width_px = v.camera.viewport_height_px = 200;
  return v;
}

// Cost and benefit of object i drawn at `level` in a group of one orthographic view of kind
// `kind` (the documented model: docs/SELECTION.md, "Views"), in double.
void groupPoint(const SyntheticScene& s, const CostCoefficients& k, const SelectionParams& params, const View& v,
                size_t i, int level, double* cost, double* benefit) {
  *cost = *benefit = 0.0;
  if (level < 0) return;
  const ViewKindWeights w = params.view_kinds[static_cast<size_t>(v.kind)];
  const double pixel = v.camera.ortho_height / v.camera.viewport_height_px;
  const double r_px = s.radii[i] / pixel;
  const double px = std::min(3.14159265358979 * r_px * r_px, 200.0 * 200.0);
  const size_t row = s.table.chain_level_offset[s.chains[i]] + static_cast<size_t>(level);
  const double geometry = k.per_triangle_ms * s.table.triangle_count[row] + k.per_vertex_ms * s.table.vertex_count[row] +
                          k.per_line_point_ms * s.table.line_point_count[row];
  *cost = w.object_cost * k.per_object_ms + w.pixel_cost * k.per_pixel_ms * px + w.geometry_cost * geometry;
  const double width = s.table.cell_width[row];
  const double q = v.pixels_per_cell * pixel / s.scales[i];
  const double accuracy = width > 0.0 ? std::min(1.0, q / width) : 1.0;
  *benefit = w.benefit * px * s.importance[i] * accuracy;
}

TEST(Views, TheTupleGreedyIsWithinHalfOfTheExactOptimum) {
  // a primary and a shadow view, each a group of one orthographic view; four objects, every
  // consistent assignment of level tuples enumerated for the exact optimum under the budget
  constexpr size_t kObjects = 4, kLevels = 4;
  SyntheticScene s = makeScene(21, kObjects, 3, kLevels);
  const glm::vec3 places[kObjects] = {{0, 0, 0}, {4, -3, 2}, {-5, 2, 30}, {6, 40, 1}};  // the third only
  for (size_t i = 0; i < kObjects; ++i) s.centers[i] = places[i];                        // seen from above,
  SelectorContext* ctx = viewContext(kObjects, 2);                                      // the fourth by neither
  const std::vector<View> views = {orthoView(ViewKind::kPrimary, 0, false), orthoView(ViewKind::kShadow, 1, true)};
  const CostCoefficients k = selectorCostModel(ctx);
  // per object, every allowed tuple as (cost, benefit)
  std::vector<std::vector<std::pair<double, double>>> options(kObjects);
  for (size_t i = 0; i < kObjects; ++i) {
    bool sees[2];
    for (size_t g = 0; g < 2; ++g) sees[g] = sphereInFrustum(computeFrustum(views[g].camera), s.centers[i], s.radii[i]);
    for (int lp = -1; lp < static_cast<int>(kLevels); ++lp)
      for (int ls = -1; ls < static_cast<int>(kLevels); ++ls) {
        if ((!sees[0] && lp >= 0) || (!sees[1] && ls >= 0)) continue;
        if (sees[0] && ls >= 0 && (lp < 0 || ls < lp)) continue;  // the shadow rule
        double c[2], b[2];
        SelectionParams params = budgetParams(1.0f);
        groupPoint(s, k, params, views[0], i, lp, &c[0], &b[0]);
        groupPoint(s, k, params, views[1], i, ls, &c[1], &b[1]);
        options[i].push_back({c[0] + c[1], b[0] + b[1]});
      }
  }
  for (float budget : {0.503f, 0.505f, 0.507f, 0.51f, 0.515f}) {
    double best = 0.0;
    size_t pick[kObjects] = {};
    for (;;) {  // every combination of one option per object
      double cost = k.per_frame_ms, benefit = 0.0;
      for (size_t i = 0; i < kObjects; ++i) {
        cost += options[i][pick[i]].first;
        benefit += options[i][pick[i]].second;
      }
      if (cost <= budget) best = std::max(best, benefit);
      size_t i = 0;
      while (i < kObjects && ++pick[i] == options[i].size()) pick[i++] = 0;
      if (i == kObjects) break;
    }
    resetSelectorHistory(ctx);
    SelectionParams params = budgetParams(budget);
    params.hysteresis = 0.0f;
    ViewRun run;
    ASSERT_TRUE(runViews(s, ctx, views, 2, params, &run));
    EXPECT_LE(run.stats.predicted_ms, budget * (1.0 + 1e-5)) << budget;
    EXPECT_LE(run.stats.total_benefit, best * (1.0 + 1e-4)) << budget;  // no better than exact
    EXPECT_GE(run.stats.total_benefit, 0.5 * best * (1.0 - 1e-4)) << budget;
    EXPECT_GT(best, 0.0);
  }
  destroySelectorContext(ctx);
}

TEST(Views, TheRulesHoldOnRandomFrames) {
  // random views (kinds, groups, X, bias, projections), must-draw and forced objects, both modes,
  // several frames each: eyes share one output, shadows never finer than the primary group where
  // it sees the object, forced levels and must-draw honoured, unflagged budgets held
  SyntheticScene s = makeScene(31, 300, 6, 6, 100.0f, true);
  for (size_t i = 0; i < s.must_draw.size(); i += 13) s.must_draw[i] = 1;
  std::vector<int8_t> forced(s.centers.size(), -1);
  for (size_t i = 5; i < forced.size(); i += 17) forced[i] = static_cast<int8_t>(i % 6);
  SelectorContext* ctx = viewContext(s.centers.size(), 4);
  std::mt19937 rng(77);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const ViewKind kinds[4] = {ViewKind::kPrimary, ViewKind::kShadow, ViewKind::kEye, ViewKind::kSecondary};
  for (int trial = 0; trial < 40; ++trial) {
    // up to four groups, each of one kind and one or two views
    const size_t groups = 1 + rng() % 4;
    std::vector<View> views;
    for (size_t g = 0; g < groups; ++g) {
      const ViewKind kind = kinds[rng() % 4];
      for (size_t k = 0, count = 1 + rng() % 2; k < count; ++k) {
        View v = kind == ViewKind::kShadow ? shadowView(static_cast<uint32_t>(10 * g), 0.5f + 4.0f * u(rng),
                                                        40.0f + 100.0f * u(rng))
                                           : primaryView(glm::vec3(20.0f * (u(rng) - 0.5f), 0.0f, 10.0f * u(rng)));
        v.kind = kind;
        v.group = static_cast<uint32_t>(10 * g);
        v.lod_bias = 0.5f + 2.0f * u(rng);
        views.push_back(v);
      }
    }
    const SelectionParams params = trial % 3 == 0 ? distanceParams() : budgetParams(0.6f + 3.0f * u(rng));
    resetSelectorHistory(ctx);
    for (int frame = 0; frame < 3; ++frame) {
      ViewRun run;
      ASSERT_TRUE(runViews(s, ctx, views, groups, params, &run, &forced)) << trial;
      int primary = -1;
      for (ViewKind k : {ViewKind::kPrimary, ViewKind::kEye, ViewKind::kSecondary})
        for (size_t g = 0; g < groups && primary < 0; ++g)
          for (const View& v : views)
            if (primary < 0 && v.group == 10 * g && v.kind == k) primary = static_cast<int>(g);
      const size_t n = s.centers.size();
      for (size_t i = 0; i < n; ++i) {
        EXPECT_EQ(run.levels[i], run.group_levels[std::max(primary, 0) * n + i]);
        bool primary_sees = false;
        for (size_t g = 0; g < groups; ++g) {
          bool sees = false;
          for (const View& v : views)
            if (v.group == 10 * g) sees |= sphereInFrustum(computeFrustum(v.camera), s.centers[i], s.radii[i]);
          const int l = run.group_levels[g * n + i];
          EXPECT_TRUE(sees || l == -1) << trial << " object " << i;
          EXPECT_TRUE(!sees || forced[i] < 0 || l == forced[i]) << trial << " object " << i;
          EXPECT_TRUE(!sees || !s.must_draw[i] || l >= 0) << trial << " object " << i;
          if (static_cast<int>(g) == primary) primary_sees = sees;
        }
        if (primary < 0 || !primary_sees) continue;
        const int p = run.group_levels[primary * n + i];
        for (size_t g = 0; g < groups; ++g) {
          const int l = run.group_levels[g * n + i];
          bool shadow = false;
          for (const View& v : views) shadow |= v.group == 10 * g && v.kind == ViewKind::kShadow;
          EXPECT_TRUE(!shadow || l < 0 || (p >= 0 && l >= p)) << trial << " object " << i;
        }
      }
      const bool held = params.mode == SelectionMode::kDistance || (run.stats.flags & kFlagOverBudget) ||
                        run.stats.predicted_ms <= params.budget_ms * (1.0 + 1e-5);
      EXPECT_TRUE(held) << trial;
    }
  }
  destroySelectorContext(ctx);
}

TEST(Views, BadInputIsRefusedWithAClearError) {
  const SyntheticScene s = makeScene(1, 10, 2, 4);
  SelectorContext* ctx = viewContext(s.centers.size(), 2);
  std::vector<int8_t> levels;
  auto errorOf = [&](std::vector<View> views, std::vector<int8_t> forced = {}) {
    SelectionJob job = makeJob(s, ctx, nullptr, levels, nullptr);
    job.views = Span<const View>(views.data(), views.size());
    if (views.empty()) job.camera = nullptr;
    job.forced_levels = Span<const int8_t>(forced.data(), forced.size());
    const char* e = job.error();
    EXPECT_EQ(job.validate(), e == nullptr);
    return std::string(e ? e : "");
  };
  EXPECT_EQ(errorOf({primaryView()}), "");
  EXPECT_EQ(errorOf(std::vector<View>(9, primaryView())), "more than 8 views");
  View mixed = eyeView(0.0f, 0);
  EXPECT_EQ(errorOf({primaryView(), mixed}), "a view group mixing kinds");
  View zero = primaryView();
  zero.camera.viewport_width_px = 0;
  EXPECT_EQ(errorOf({zero}), "a view with a zero viewport");
  View nan = primaryView();
  nan.camera.eye.x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(errorOf({nan}).find("not finite"), std::string::npos);
  View bias = primaryView();
  bias.lod_bias = 0.0f;
  EXPECT_NE(errorOf({bias}).find("lod_bias"), std::string::npos);
  EXPECT_NE(errorOf({primaryView(), shadowView(1), shadowView(2)}).find("max_view_groups"), std::string::npos);
  std::vector<int8_t> forced(s.centers.size(), -1);
  forced[4] = 4;  // chains of 4 levels: 0..3
  EXPECT_EQ(errorOf({primaryView()}, forced), "a forced level out of its chain's range");
  forced[4] = -2;
  EXPECT_EQ(errorOf({primaryView()}, forced), "a forced level out of its chain's range");
  {
    std::vector<int8_t> small(s.centers.size());
    SelectionJob j = makeJob(s, ctx, nullptr, levels, nullptr);
    const View one = primaryView();
    j.views = Span<const View>(&one, 1);
    j.group_levels_out = Span<int8_t>(small.data(), small.size() - 1);
    EXPECT_NE(std::string(j.error()).find("group_levels_out"), std::string::npos);
  }
  // a context without view memory refuses views and forced levels alike
  SelectorContext* plain = test::makeContext(s.centers.size());
  const Camera cam = makeCamera();
  SelectionJob job = makeJob(s, plain, &cam, levels, nullptr);
  forced[4] = 1;
  job.forced_levels = Span<const int8_t>(forced.data(), forced.size());
  EXPECT_NE(std::string(job.error()).find("max_view_groups"), std::string::npos);
  EXPECT_FALSE(job.run());
  destroySelectorContext(plain);
  destroySelectorContext(ctx);
}

}  // namespace
}  // namespace scenelod::selection
