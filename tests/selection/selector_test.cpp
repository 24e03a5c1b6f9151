#include "scenelod/selection/selector.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <random>
#include <thread>
#include <vector>

#include <functional>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "selection/selection_fixtures.h"

#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
// every heap allocation of the test program is counted, to show run() makes none
namespace {
std::atomic<size_t> g_heap_allocations{0};
}
void* operator new(size_t n) {
  g_heap_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }

using namespace scenelod;
using namespace scenelod::selection;
using namespace scenelod::selection::test;

namespace {

struct CountingAllocator {
  size_t allocations = 0, frees = 0;
  static void* allocate(void* user, size_t bytes, size_t alignment) {
    ++static_cast<CountingAllocator*>(user)->allocations;
    return defaultAllocator().allocate(nullptr, bytes, alignment);
  }
  static void release(void* user, void* p) {
    ++static_cast<CountingAllocator*>(user)->frees;
    defaultAllocator().free(nullptr, p);
  }
};

// distance-mode reference: the coarsest level with w * scale <= X * R (R at D - radius)
int referenceDistanceLevel(const SyntheticScene& s, const Camera& cam, size_t i, float x) {
  const LevelTable t = s.table.view();
  const uint32_t b = t.chain_level_offset[s.chains[i]], e = t.chain_level_offset[s.chains[i] + 1];
  const float d = glm::length(s.centers[i] - cam.eye) - s.radii[i];
  const float q = x * pixelSize(cam, d) / s.scales[i];
  int level = 0;
  for (uint32_t r = b; r < e; ++r)
    if (t.cell_width[r] <= q) level = static_cast<int>(r - b);
  return level;
}

}  // namespace

TEST(Selector, ContextCreationRefusesBadConfigs) {
  SelectorConfig cfg;
  EXPECT_EQ(createSelectorContext(cfg), nullptr);  // no objects
  cfg.max_object_count = 10;
  cfg.max_levels_per_chain = 0;
  EXPECT_EQ(createSelectorContext(cfg), nullptr);
  cfg.max_levels_per_chain = 65;
  EXPECT_EQ(createSelectorContext(cfg), nullptr);
  cfg.max_levels_per_chain = 8;
  cfg.calibration.forgetting = 0.0;
  EXPECT_EQ(createSelectorContext(cfg), nullptr);
  cfg.calibration.forgetting = 0.9;
  // the shadow scales' fit: forgetting in (0, 1], a positive finite ridge
  for (const double bad : {0.0, -0.5, 1.5, std::nan("")}) {
    cfg.calibration.shadow_forgetting = bad;
    EXPECT_EQ(createSelectorContext(cfg), nullptr) << "shadow_forgetting " << bad;
  }
  cfg.calibration.shadow_forgetting = 0.998;
  for (const double bad : {0.0, -1.0, std::numeric_limits<double>::infinity(), std::nan("")}) {
    cfg.calibration.shadow_prior_weight = bad;
    EXPECT_EQ(createSelectorContext(cfg), nullptr) << "shadow_prior_weight " << bad;
  }
  cfg.calibration.shadow_prior_weight = 1.0;
  {
    Owned good(createSelectorContext(cfg));
    EXPECT_NE(good.ctx, nullptr);  // the same config with sane settings is accepted
  }
  Allocator failing;
  failing.allocate = [](void*, size_t, size_t) -> void* { return nullptr; };
  failing.free = [](void*, void*) {};
  cfg.allocator = failing;
  EXPECT_EQ(createSelectorContext(cfg), nullptr);  // out of memory is reported, not thrown
}

// validate's chain check runs two vectors at a time (SSE2: 8 objects, AVX2: 16) and the rest one
// by one: a chain id out of range is found at every position, also ids with the top bit set (the
// unsigned compare is a signed one after a sign flip), on both code paths.
TEST(Selector, ValidateFindsAChainIdOutOfRangeAtEveryPosition) {
  SyntheticScene s = makeScene(2, 45, 3, 5);
  SelectorConfig cfg;
  cfg.max_object_count = 45;
  for (const bool sse2_only : {false, true}) {
    cfg.sse2_only = sse2_only;
    Owned o(createSelectorContext(cfg));
    const Camera cam = makeCamera();
    std::vector<int8_t> levels;
    SelectionStats st;
    SelectionJob job = makeJob(s, o.ctx, &cam, levels, &st);
    ASSERT_TRUE(job.validate());
    std::vector<uint32_t> chains = s.chains;
    job.chains = Span<const uint32_t>(chains.data(), chains.size());
    for (size_t i = 0; i < chains.size(); ++i) {
      for (const uint32_t bad : {3u, 0x7fffffffu, 0x80000000u, 0xffffffffu}) {
        chains[i] = bad;
        EXPECT_FALSE(job.validate()) << "object " << i << " chain " << bad << " sse2 " << sse2_only;
      }
      chains[i] = 2;  // the last chain: valid
      EXPECT_TRUE(job.validate()) << "object " << i << " sse2 " << sse2_only;
      chains[i] = s.chains[i];
    }
  }
}

TEST(Selector, ValidateRefusesEachInvalidField) {
  SyntheticScene s = makeScene(1, 20, 3, 5);
  Owned o(makeContext(20));
  const Camera cam = makeCamera();
  std::vector<int8_t> levels;
  SelectionStats st;
  const SelectionJob good = makeJob(s, o.ctx, &cam, levels, &st);
  ASSERT_TRUE(good.validate());
  std::vector<float> short_f(19, 1.0f);
  std::vector<int8_t> short_l(19);
  std::vector<uint32_t> bad_chain = s.chains;
  bad_chain[7] = 3;
  std::vector<float> widths = s.table.cell_width;
  widths[2] = widths[1] * 0.5f;  // decreasing inside chain 0
  std::vector<float> nan_widths = s.table.cell_width;
  nan_widths[1] = std::nanf("");
  std::vector<uint32_t> offsets = s.table.chain_level_offset;
  offsets.back() += 1;
  Camera bad_cam = cam;
  bad_cam.target = bad_cam.eye;
  Owned small(makeContext(10));
  SelectorConfig few_levels;
  few_levels.max_object_count = 20;
  few_levels.max_levels_per_chain = 4;
  Owned narrow(createSelectorContext(few_levels));

  std::vector<std::function<void(SelectionJob&)>> breakers = {
      [](SelectionJob& j) { j.context = nullptr; },
      [](SelectionJob& j) { j.camera = nullptr; },
      [&](SelectionJob& j) { j.camera = &bad_cam; },
      [&](SelectionJob& j) { j.context = small.ctx; },  // more objects than the context holds
      [&](SelectionJob& j) { j.context = narrow.ctx; },  // more levels than the context holds
      [&](SelectionJob& j) { j.radii = Span<const float>(short_f.data(), short_f.size()); },
      [&](SelectionJob& j) { j.max_scales = Span<const float>(short_f.data(), short_f.size()); },
      [&](SelectionJob& j) { j.importance = Span<const float>(short_f.data(), short_f.size()); },
      [&](SelectionJob& j) { j.visible_fraction = Span<const float>(short_f.data(), short_f.size()); },
      [&](SelectionJob& j) { j.focus = Span<const float>(short_f.data(), short_f.size()); },
      [&](SelectionJob& j) { j.motion = Span<const float>(short_f.data(), short_f.size()); },
      [&](SelectionJob& j) { j.levels_out = Span<int8_t>(short_l.data(), short_l.size()); },
      [&](SelectionJob& j) { j.centers = Span<const glm::vec3>(nullptr, 20); },
      [&](SelectionJob& j) { j.chains = Span<const uint32_t>(bad_chain.data(), bad_chain.size()); },
      [&](SelectionJob& j) { j.levels.cell_width = Span<const float>(widths.data(), widths.size()); },
      [&](SelectionJob& j) { j.levels.cell_width = Span<const float>(nan_widths.data(), nan_widths.size()); },
      [&](SelectionJob& j) { j.levels.chain_level_offset = Span<const uint32_t>(offsets.data(), offsets.size()); },
      [&](SelectionJob& j) { j.levels.triangle_count.count -= 1; },
      [](SelectionJob& j) { j.params.budget_ms = 0.0f; },
      [](SelectionJob& j) { j.params.budget_ms = std::nanf(""); },
      [](SelectionJob& j) { j.params.pixels_per_cell = 0.0f; },
      [](SelectionJob& j) { j.params.hysteresis = -0.5f; },
  };
  for (size_t b = 0; b < breakers.size(); ++b) {
    SelectionJob j = good;
    breakers[b](j);
    std::fill(levels.begin(), levels.end(), int8_t(42));
    EXPECT_FALSE(j.validate()) << "breaker " << b;
    EXPECT_FALSE(j.run()) << "breaker " << b;
    EXPECT_EQ(levels[0], 42) << "outputs untouched, breaker " << b;
  }
  // distance mode needs no budget
  SelectionJob d = good;
  d.params.mode = SelectionMode::kDistance;
  d.params.budget_ms = 0.0f;
  EXPECT_TRUE(d.run());
}

TEST(Selector, RunAllocatesNothingAfterCreation) {
  SyntheticScene s = makeScene(2, 3000, 10, 8, 200.0f, true);
  CountingAllocator counter;
  SelectorConfig cfg;
  cfg.max_object_count = 3000;
  cfg.bracket_capacity = 64;  // force the price search
  cfg.allocator.allocate = CountingAllocator::allocate;
  cfg.allocator.free = CountingAllocator::release;
  cfg.allocator.user = &counter;
  SelectorContext* ctx = createSelectorContext(cfg);
  ASSERT_NE(ctx, nullptr);
  EXPECT_EQ(counter.allocations, 1u);
  std::vector<int8_t> levels;
  SelectionStats st;
  Camera cam = makeCamera();
  SelectionJob job = makeJob(s, ctx, &cam, levels, &st);
  std::vector<float> cost(s.centers.size());
  job.cost_ms_out = Span<float>(cost.data(), cost.size());
  const size_t before = g_heap_allocations.load();
  for (int frame = 0; frame < 30; ++frame) {
    cam.eye = glm::vec3(0.1f * frame, 0.0f, -0.5f * frame);
    cam.target = cam.eye + glm::vec3(0, 0, -1);
    job.params.mode = frame % 3 == 2 ? SelectionMode::kDistance : SelectionMode::kBudget;
    job.params.algorithm = frame % 2 ? BudgetAlgorithm::kGreedy : BudgetAlgorithm::kLagrangian;
    job.params.budget_ms = 2.0f + frame;
    reportFrameTime(ctx, st.frame, 5.0f);
    ASSERT_TRUE(job.run());
  }
  EXPECT_EQ(g_heap_allocations.load(), before);
  EXPECT_EQ(counter.allocations, 1u);
  destroySelectorContext(ctx);
  EXPECT_EQ(counter.frees, 1u);
}

TEST(Selector, FramesWithViewsAllocateNothingAfterCreation) {
  SyntheticScene s = makeScene(3, 2000, 10, 8, 200.0f, true);
  CountingAllocator counter;
  SelectorConfig cfg;
  cfg.max_object_count = 2000;
  cfg.max_view_groups = 2;
  cfg.allocator.allocate = CountingAllocator::allocate;
  cfg.allocator.free = CountingAllocator::release;
  cfg.allocator.user = &counter;
  SelectorContext* ctx = createSelectorContext(cfg);
  ASSERT_NE(ctx, nullptr);
  EXPECT_EQ(counter.allocations, 2u);  // the context and its view memory
  std::vector<int8_t> levels, group_levels(2 * s.centers.size()), forced(s.centers.size(), -1);
  for (size_t i = 0; i < forced.size(); i += 11) forced[i] = 2;
  SelectionStats st;
  SelectionJob job = makeJob(s, ctx, nullptr, levels, &st);
  View views[3];
  views[2].kind = ViewKind::kShadow;
  views[2].group = 1;
  views[2].pixels_per_cell = 4.0f;
  views[2].camera.projection = Projection::kOrthographic;
  views[2].camera.eye = glm::vec3(0.0f, 300.0f, -100.0f);
  views[2].camera.target = glm::vec3(0.0f, 0.0f, -100.0f);
  views[2].camera.up = glm::vec3(0.0f, 0.0f, -1.0f);
  views[2].camera.ortho_height = 150.0f;
  views[2].camera.far_plane = 1000.0f;
  job.views = Span<const View>(views, 3);
  job.group_levels_out = Span<int8_t>(group_levels.data(), group_levels.size());
  job.forced_levels = Span<const int8_t>(forced.data(), forced.size());
  const size_t before = g_heap_allocations.load();
  for (int frame = 0; frame < 20; ++frame) {
    for (int e = 0; e < 2; ++e) {
      views[e].camera = makeCamera(glm::vec3(0.1f * frame + 0.06f * e, 0.0f, -0.5f * frame));
      views[e].kind = ViewKind::kEye;
    }
    job.params.mode = frame % 3 == 2 ? SelectionMode::kDistance : SelectionMode::kBudget;
    job.params.budget_ms = 2.0f + frame;
    reportFrameTime(ctx, st.frame, 5.0f);
    ASSERT_TRUE(job.run()) << job.error();
  }
  EXPECT_EQ(g_heap_allocations.load(), before);
  EXPECT_EQ(counter.allocations, 2u);
  destroySelectorContext(ctx);
  EXPECT_EQ(counter.frees, 2u);
}

TEST(Selector, DistanceModePicksCoarsestAccurateEnoughLevel) {
  SyntheticScene s = makeScene(3, 500, 7, 8, 150.0f, true);
  Owned o(makeContext(500));
  const Camera cam = makeCamera();
  const Frustum fr = computeFrustum(cam);
  for (float x : {1.0f, 4.0f}) {
    resetSelectorHistory(o.ctx);
    std::vector<int8_t> levels;
    SelectionStats st;
    SelectionJob job = makeJob(s, o.ctx, &cam, levels, &st);
    job.params.mode = SelectionMode::kDistance;
    job.params.pixels_per_cell = x;
    ASSERT_TRUE(job.run());
    size_t drawn = 0, coarse = 0;
    for (size_t i = 0; i < s.centers.size(); ++i) {
      if (!sphereInFrustum(fr, s.centers[i], s.radii[i])) {
        EXPECT_EQ(levels[i], -1);
        continue;
      }
      ++drawn;
      EXPECT_EQ(levels[i], referenceDistanceLevel(s, cam, i, x)) << "object " << i;
      coarse += levels[i] > 0;
    }
    EXPECT_EQ(st.drawn_count, drawn);
    EXPECT_GT(coarse, drawn / 4);  // the scene exercises more than level 0
  }
}

TEST(Selector, ObjectsBehindTheCameraAreNeverDrawn) {
  SyntheticScene s = makeScene(4, 400, 5, 6, 60.0f, true);
  for (size_t i = 0; i < s.must_draw.size(); i += 3) s.must_draw[i] = 1;  // even must-draw ones
  Owned o(makeContext(400));
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int frame = 0; frame < 40; ++frame) {
    Camera cam = makeCamera(glm::vec3(u(rng) * 20, u(rng) * 5, u(rng) * 20));
    cam.target = cam.eye + glm::vec3(u(rng), 0.2f * u(rng), u(rng) + 0.01f);
    std::vector<int8_t> levels;
    SelectionStats st;
    SelectionJob job = makeJob(s, o.ctx, &cam, levels, &st);
    job.params.mode = frame % 2 ? SelectionMode::kDistance : SelectionMode::kBudget;
    job.params.budget_ms = 1e6f;
    ASSERT_TRUE(job.run());
    const glm::vec3 fwd = glm::normalize(cam.target - cam.eye);
    for (size_t i = 0; i < s.centers.size(); ++i) {
      if (glm::dot(s.centers[i] - cam.eye, fwd) < -s.radii[i]) {
        EXPECT_EQ(levels[i], -1) << "frame " << frame;
      }
    }
  }
}

TEST(Selector, UnlimitedBudgetEqualsDistanceModeAlongAPath) {
  SyntheticScene s = makeScene(5, 800, 9, 8, 120.0f, true);
  Owned budget_ctx(makeContext(800, 32)), dist_ctx(makeContext(800));
  for (int frame = 0; frame < 60; ++frame) {
    // approach and turn: levels switch both ways, hysteresis in play
    const float t = frame / 59.0f;
    Camera cam = makeCamera(glm::vec3(10.0f * std::sin(3 * t), 0.0f, 40.0f - 100.0f * t));
    cam.target = cam.eye + glm::vec3(std::sin(2 * t), 0.0f, -1.0f);
    std::vector<int8_t> a, b;
    SelectionStats sa, sb;
    SelectionJob ja = makeJob(s, budget_ctx.ctx, &cam, a, &sa);
    ja.params.budget_ms = 1e9f;
    ja.params.hysteresis = 0.25f;
    ja.params.algorithm = frame % 2 ? BudgetAlgorithm::kGreedy : BudgetAlgorithm::kLagrangian;
    SelectionJob jb = makeJob(s, dist_ctx.ctx, &cam, b, &sb);
    jb.params.mode = SelectionMode::kDistance;
    jb.params.hysteresis = 0.25f;
    ASSERT_TRUE(ja.run());
    ASSERT_TRUE(jb.run());
    ASSERT_EQ(a, b) << "frame " << frame;
    EXPECT_EQ(sa.switch_count, sb.switch_count);
    EXPECT_EQ(sa.flags, 0u);
  }
}

TEST(Selector, PredictedCostStaysWithinBudgetOnUnflaggedFrames) {
  SyntheticScene s = makeScene(6, 2000, 12, 8, 150.0f, true);
  for (size_t i = 0; i < s.must_draw.size(); i += 97) s.must_draw[i] = 1;
  Owned o(makeContext(2000, 128));
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  size_t flagged = 0, unflagged = 0;
  for (int frame = 0; frame < 80; ++frame) {
    Camera cam = makeCamera(glm::vec3(0.0f, 0.0f, 30.0f - frame));
    std::vector<int8_t> levels;
    std::vector<float> cost(s.centers.size());
    SelectionStats st;
    SelectionJob job = makeJob(s, o.ctx, &cam, levels, &st);
    job.cost_ms_out = Span<float>(cost.data(), cost.size());
    job.params.budget_ms = 0.3f + 30.0f * u(rng);
    job.params.algorithm = frame % 2 ? BudgetAlgorithm::kGreedy : BudgetAlgorithm::kLagrangian;
    job.params.stop_at_first_non_fitting = frame % 5 != 0;
    ASSERT_TRUE(job.run());
    double sum = selectorCostModel(o.ctx).per_frame_ms;
    for (float c : cost) sum += c;
    EXPECT_NEAR(sum, st.predicted_ms, 1e-6 * st.predicted_ms);
    if (st.flags & kFlagOverBudget) {
      ++flagged;
      EXPECT_GT(st.mandatory_ms, job.params.budget_ms);
    } else {
      ++unflagged;
      EXPECT_LE(st.predicted_ms, job.params.budget_ms * (1.0 + 1e-9)) << "frame " << frame;
    }
    // must-draw objects in view are drawn, always
    const Frustum fr = computeFrustum(cam);
    for (size_t i = 0; i < s.centers.size(); ++i) {
      if (s.must_draw[i] && sphereInFrustum(fr, s.centers[i], s.radii[i])) {
        EXPECT_GE(levels[i], 0);
      }
    }
  }
  EXPECT_GT(unflagged, 40u);
}

TEST(Selector, TinyBudgetDropsObjectsButKeepsMustDrawAndFlags) {
  SyntheticScene s = makeScene(7, 300, 4, 6, 40.0f);
  s.must_draw[3] = s.must_draw[10] = 1;
  Owned o(makeContext(300));
  const Camera cam = makeCamera(glm::vec3(0, 0, 5));
  std::vector<int8_t> levels;
  SelectionStats st;
  SelectionJob job = makeJob(s, o.ctx, &cam, levels, &st);
  job.params.min_drop_px = 0.0f;  // any object may be dropped (the drop policy off)
  job.params.budget_ms = 0.51f;  // barely above the per-frame constant
  ASSERT_TRUE(job.run());
  EXPECT_TRUE(st.flags & kFlagObjectsDropped);
  EXPECT_GT(st.dropped_count, 200u);
  const Frustum fr = computeFrustum(cam);
  for (size_t i : {3, 10}) {
    if (!sphereInFrustum(fr, s.centers[i], s.radii[i])) continue;
    {
      EXPECT_GE(levels[i], 0);
      // at their cheapest (coarsest) level
      const uint32_t b = s.table.chain_level_offset[s.chains[i]], e = s.table.chain_level_offset[s.chains[i] + 1];
      EXPECT_EQ(levels[i], static_cast<int>(e - b) - 1);
    }
  }
  // far below even the must-draw objects: flagged over budget, must-draw still drawn
  job.params.budget_ms = 0.1f;
  ASSERT_TRUE(job.run());
  EXPECT_TRUE(st.flags & kFlagOverBudget);
  EXPECT_EQ(st.drawn_count, 2u);
}

// The heap greedy on `greedy` and the Lagrangian form on `lagrangian`, one frame each from the same
// camera and budget: the levels that differ, and both frames' stats.
struct GreedyVsLagrangian {
  size_t differ = 0;
  SelectionStats greedy, lagrangian;
};
GreedyVsLagrangian runGreedyAndLagrangian(const SyntheticScene& s, Owned& greedy, Owned& lagrangian, const Camera& cam,
                                          float budget_ms, float hysteresis = SelectionParams().hysteresis) {
  GreedyVsLagrangian r;
  std::vector<int8_t> a, b;
  SelectionJob ja = makeJob(s, greedy.ctx, &cam, a, &r.greedy);
  SelectionJob jb = makeJob(s, lagrangian.ctx, &cam, b, &r.lagrangian);
  ja.params.algorithm = BudgetAlgorithm::kGreedy;
  jb.params.algorithm = BudgetAlgorithm::kLagrangian;
  ja.params.budget_ms = jb.params.budget_ms = budget_ms;
  ja.params.hysteresis = jb.params.hysteresis = hysteresis;
  const bool ran = ja.run() && jb.run();
  EXPECT_TRUE(ran);
  if (!ran) r.differ = a.size();
  for (size_t i = 0; ran && i < a.size(); ++i) r.differ += a[i] != b[i];
  return r;
}

TEST(Selector, LagrangianMatchesGreedyChoices) {
  // the bracket capacity (2 or 16..31) is small: some frames find the budget's edge from the price
  // histogram alone, others need passes over the objects; both must match the greedy
  size_t histogram_only = 0, with_passes = 0;
  for (uint32_t seed = 20; seed < 32; ++seed) {
    SyntheticScene s = makeScene(seed, 1500, 6, 8, 120.0f, true);
    Owned g(makeContext(1500)), l(makeContext(1500, seed % 2 ? 16 + seed : 2));
    std::mt19937 rng(seed);
    for (int frame = 0; frame < 6; ++frame) {
      const Camera cam = makeCamera(glm::vec3(0.0f, 1.0f, 20.0f - 4.0f * frame));
      const float budget_ms = 1.0f + static_cast<float>(rng() % 4000) / 100.0f;
      const GreedyVsLagrangian r = runGreedyAndLagrangian(s, g, l, cam, budget_ms);
      EXPECT_EQ(r.differ, 0u) << "seed " << seed << " frame " << frame;
      EXPECT_EQ(r.greedy.predicted_ms, r.lagrangian.predicted_ms);
      if (r.lagrangian.lambda > 0.0) {  // the budget binds
        if (r.lagrangian.search_passes > 0) ++with_passes; else ++histogram_only;
      }
    }
  }
  std::printf("binding frames: %zu from the histogram alone, %zu with passes\n", histogram_only, with_passes);
  EXPECT_GT(histogram_only, 0u);
  EXPECT_GT(with_passes, 0u);
}

TEST(Selector, LagrangianMatchesGreedyAlongASmoothPath) {
  // small camera steps: the Lagrangian form starts from last frame's price (its predicted bracket,
  // the histogram, or passes when a bracket overflows the small capacity); every frame must give the
  // greedy's choice
  for (uint32_t seed = 40; seed < 44; ++seed) {
    SyntheticScene s = makeScene(seed, 1500, 6, 8, 120.0f, true);
    Owned g(makeContext(1500)), l(makeContext(1500, seed % 2 ? 64 : 8));
    size_t binding = 0;
    for (int frame = 0; frame < 40; ++frame) {
      const Camera cam = makeCamera(glm::vec3(0.05f * frame, 1.0f, 20.0f - 0.2f * frame));
      const GreedyVsLagrangian r = runGreedyAndLagrangian(s, g, l, cam, 1.5f);
      EXPECT_EQ(r.differ, 0u) << "seed " << seed << " frame " << frame;
      EXPECT_EQ(r.greedy.predicted_ms, r.lagrangian.predicted_ms);
      EXPECT_EQ(r.greedy.total_benefit, r.lagrangian.total_benefit);
      binding += r.lagrangian.dropped_count > 0;
    }
    EXPECT_GT(binding, 30u) << "the budget should bind on most frames";
  }
}

TEST(Selector, LagrangianMatchesGreedyOnDegenerateChainsAlongAPath) {
  // what the settling test must leave to the hulls: without hysteresis two levels with the same
  // width and counts are the same point (the hull keeps the coarser), a chain longer than the 8
  // lanes, must-draw objects, objects whose chain changes; every frame must still give the
  // greedy's choice
  for (uint32_t seed = 50; seed < 53; ++seed) {
    SyntheticScene s = makeScene(seed, 1500, 6, 8, 120.0f, true);
    const float w[8] = {0.0f, 0.01f, 0.02f, 0.02f, 0.04f, 0.08f, 0.08f, 0.16f};
    const uint32_t t[8] = {20000, 8000, 3000, 3000, 1200, 500, 500, 100};
    const uint32_t v[8] = {10000, 4000, 1500, 1500, 600, 250, 250, 50};
    const uint32_t lp[8] = {0, 10, 10, 10, 10, 10, 10, 10};
    const uint32_t twins = s.table.addChain(Span<const float>(w, 8), Span<const uint32_t>(t, 8),
                                            Span<const uint32_t>(v, 8), Span<const uint32_t>(lp, 8));
    std::vector<float> lw(12);
    std::vector<uint32_t> lt(12), lv(12), llp(12, 4);
    for (size_t k = 0; k < 12; ++k) {
      lw[k] = k == 0 ? 0.0f : 0.004f * static_cast<float>(1u << (k - 1));
      lt[k] = 40000u >> k;
      lv[k] = lt[k] / 2 + 2;
    }
    const uint32_t longer = s.table.addChain(Span<const float>(lw.data(), 12), Span<const uint32_t>(lt.data(), 12),
                                             Span<const uint32_t>(lv.data(), 12), Span<const uint32_t>(llp.data(), 12));
    for (size_t i = 0; i < s.chains.size(); ++i) {
      if (i % 5 == 1) s.chains[i] = twins;
      if (i % 7 == 2) s.chains[i] = longer;
      if (i % 97 == 3) s.must_draw[i] = 1;
    }
    SelectorConfig cfg;
    cfg.max_object_count = 1500;
    cfg.max_levels_per_chain = 12;
    Owned g(createSelectorContext(cfg));
    cfg.bracket_capacity = 64;
    Owned l(createSelectorContext(cfg));
    for (int frame = 0; frame < 30; ++frame) {
      // objects moved between chains keep their level index: last frame's level can then be any
      // level of the new chain, the finer of two twins included
      if (frame % 6 == 5)
        for (size_t i = 0; i < s.chains.size(); i += 3) s.chains[i] = s.chains[i] == twins ? 0 : twins;
      const Camera cam = makeCamera(glm::vec3(0.05f * frame, 1.0f, 20.0f - 0.2f * frame));
      const GreedyVsLagrangian r = runGreedyAndLagrangian(s, g, l, cam, 1.5f, 0.0f);
      EXPECT_EQ(r.differ, 0u) << "seed " << seed << " frame " << frame;
      EXPECT_EQ(r.greedy.predicted_ms, r.lagrangian.predicted_ms);
      EXPECT_EQ(r.greedy.total_benefit, r.lagrangian.total_benefit);
    }
  }
}

TEST(Selector, MustDrawObjectsEnteringTheViewOnWarmFramesAreDrawn) {
  // a camera panning sideways: must-draw objects come into view with last frame's level "not
  // drawn", which the settling test must not keep; every frame must draw them and give the greedy's
  // choice
  SyntheticScene s = makeScene(61, 1500, 6, 8, 120.0f);
  for (size_t i = 0; i < s.must_draw.size(); i += 10) s.must_draw[i] = 1;
  Owned g(makeContext(1500)), l(makeContext(1500, 64));
  size_t entering = 0;
  std::vector<int8_t> last(s.centers.size(), -1);
  for (int frame = 0; frame < 30; ++frame) {
    const Camera cam = makeCamera(glm::vec3(-40.0f + 1.5f * frame, 1.0f, 20.0f));
    std::vector<int8_t> levels;
    SelectionStats st;
    SelectionJob job = makeJob(s, l.ctx, &cam, levels, &st);
    job.params.budget_ms = 3.0f;
    ASSERT_TRUE(job.run());
    std::vector<int8_t> greedy_levels;
    SelectionStats greedy_st;
    SelectionJob greedy_job = makeJob(s, g.ctx, &cam, greedy_levels, &greedy_st);
    greedy_job.params.budget_ms = 3.0f;
    greedy_job.params.algorithm = BudgetAlgorithm::kGreedy;
    ASSERT_TRUE(greedy_job.run());
    EXPECT_EQ(levels, greedy_levels) << "frame " << frame;
    EXPECT_EQ(st.predicted_ms, greedy_st.predicted_ms) << "frame " << frame;
    EXPECT_GT(st.dropped_count, 0u) << "frame " << frame;
    const Frustum fr = computeFrustum(cam);
    for (size_t i = 0; i < s.centers.size(); i += 10) {
      if (!sphereInFrustum(fr, s.centers[i], s.radii[i])) continue;
      EXPECT_GE(levels[i], 0) << "frame " << frame << " object " << i;
      entering += frame > 0 && last[i] < 0;
    }
    last = levels;
  }
  EXPECT_GT(entering, 20u);
}

TEST(Selector, LagrangianMatchesGreedyWhenTheHalfFallbackWinsOnAWarmFrame) {
  // few objects and a budget that moves a little per frame: the first upgrade that does not fit,
  // alone, sometimes beats the greedy (kFlagSplitFallback), and on some frames it starts to. On
  // such a warm frame (last frame's price known, the camera barely moving) most slots settle at
  // last frame's levels and get no hull; the fallback must put them at their base ("not drawn")
  // all the same, so every frame must equal the heap greedy's
  size_t warm_fallbacks = 0, switched_to_fallback = 0;
  for (uint32_t seed = 600; seed < 800; ++seed) {
    std::mt19937 rng(seed);
    const size_t objects = 6 + rng() % 10;
    SyntheticScene s = makeScene(seed, objects, 3, 2 + rng() % 6, 12.0f);
    Owned g(makeContext(objects)), l(makeContext(objects));
    const float budget0 = 0.05f + static_cast<float>(rng() % 1000) / 1000.0f;
    const float growth = rng() % 2 ? 1.01f : 1.0f / 1.01f;
    float budget_ms = budget0;
    bool fallback_before = false;
    for (int frame = 0; frame < 40; ++frame, budget_ms *= growth) {
      const Camera cam = makeCamera(glm::vec3(0.001f * frame, 0.0f, 6.0f));
      const GreedyVsLagrangian r = runGreedyAndLagrangian(s, g, l, cam, budget_ms, 0.0f);
      EXPECT_EQ(r.differ, 0u) << "seed " << seed << " frame " << frame;
      EXPECT_EQ(r.greedy.predicted_ms, r.lagrangian.predicted_ms) << "seed " << seed << " frame " << frame;
      EXPECT_EQ(r.greedy.total_benefit, r.lagrangian.total_benefit) << "seed " << seed << " frame " << frame;
      EXPECT_EQ(r.greedy.flags, r.lagrangian.flags) << "seed " << seed << " frame " << frame;
      const bool fallback = (r.lagrangian.flags & kFlagSplitFallback) != 0;
      warm_fallbacks += frame > 0 && fallback;
      switched_to_fallback += frame > 0 && fallback && !fallback_before;
      fallback_before = fallback;
    }
  }
  std::printf("warm frames with the half fallback: %zu, %zu of them after a frame without\n", warm_fallbacks,
              switched_to_fallback);
  EXPECT_GE(switched_to_fallback, 3u);
}

TEST(Selector, ObjectsOnAChainWithoutLevelsAreLikeCulledOnes) {
  // a chain with no level: its objects are never slots. The same scene with those objects moved
  // behind the camera instead must give the same frames, bit for bit, in both modes
  SyntheticScene with_empty = makeScene(31, 400, 4, 6, 60.0f);
  SyntheticScene culled = with_empty;
  const uint32_t empty = with_empty.table.addChain(Span<const float>(), Span<const uint32_t>(), Span<const uint32_t>(),
                                                   Span<const uint32_t>());
  culled.table = with_empty.table;  // the same table (the empty chain unused)
  for (size_t i = 0; i < with_empty.chains.size(); i += 4) {
    with_empty.chains[i] = empty;
    culled.centers[i] = glm::vec3(0.0f, 0.0f, 1000.0f);  // behind the camera, which looks down -z
  }
  Owned a(makeContext(400)), b(makeContext(400));
  for (int frame = 0; frame < 6; ++frame) {
    const Camera cam = makeCamera(glm::vec3(0.1f * frame, 0.0f, 5.0f));
    std::vector<int8_t> la, lb;
    SelectionStats sa, sb;
    SelectionJob ja = makeJob(with_empty, a.ctx, &cam, la, &sa), jb = makeJob(culled, b.ctx, &cam, lb, &sb);
    ja.params.mode = jb.params.mode = frame % 3 == 2 ? SelectionMode::kDistance : SelectionMode::kBudget;
    ja.params.budget_ms = jb.params.budget_ms = 2.0f;
    ASSERT_TRUE(ja.run());
    ASSERT_TRUE(jb.run());
    EXPECT_EQ(la, lb) << "frame " << frame;
    EXPECT_EQ(0, std::memcmp(&sa, &sb, sizeof(sa))) << "frame " << frame;
    for (size_t i = 0; i < la.size(); i += 4) EXPECT_EQ(la[i], -1) << "object " << i;
    EXPECT_GE(sa.culled_count, 100u);
    EXPECT_GT(sa.drawn_count, 0u);
  }
}

namespace {

// Runs one frame (budget 6 ms) on two contexts and expects the same levels, costs and stats, bit
// for bit. report_ms >= 0: both contexts first get that time reported for frame 0.
void expectSameFrame(const SyntheticScene& s, SelectorContext* a, SelectorContext* b, const Camera& cam,
                     SelectionMode mode, float report_ms, int frame) {
  std::vector<int8_t> la, lb;
  std::vector<float> ca(s.centers.size()), cb(s.centers.size());
  SelectionStats sa, sb;
  SelectionJob ja = makeJob(s, a, &cam, la, &sa), jb = makeJob(s, b, &cam, lb, &sb);
  ja.cost_ms_out = Span<float>(ca.data(), ca.size());
  jb.cost_ms_out = Span<float>(cb.data(), cb.size());
  ja.params.budget_ms = jb.params.budget_ms = 6.0f;
  ja.params.mode = jb.params.mode = mode;
  if (report_ms >= 0.0f) {
    reportFrameTime(a, sa.frame, report_ms);
    reportFrameTime(b, sb.frame, report_ms);
  }
  ASSERT_TRUE(ja.run());
  ASSERT_TRUE(jb.run());
  EXPECT_EQ(la, lb) << "frame " << frame;
  EXPECT_EQ(0, std::memcmp(ca.data(), cb.data(), ca.size() * sizeof(float))) << "frame " << frame;
  EXPECT_EQ(0, std::memcmp(&sa, &sb, sizeof(sa))) << "frame " << frame;
}

}  // namespace

// The integer cost features of a budget frame are the sums of the drawn levels' counts, whether the
// write-out counts drawn slots per level-table row (fewer rows than slots) or gathers every slot's
// row (more rows than slots).
TEST(Selector, BudgetFeaturesAreTheSumsOfTheDrawnLevels) {
  struct Case { size_t objects, chains; };
  for (const Case c : {Case{3000, 8}, Case{60, 40}}) {
    SyntheticScene s = makeScene(21, c.objects, c.chains, 8, 100.0f, true);
    const LevelTable t = s.table.view();
    Owned ctx(makeContext(c.objects, 100));
    size_t fewer_rows_than_slots = 0;
    for (int frame = 0; frame < 8; ++frame) {
      const Camera cam = makeCamera(glm::vec3(frame * 0.4f, 0.0f, 10.0f - frame * 0.8f));
      std::vector<int8_t> levels;
      SelectionStats st;
      SelectionJob job = makeJob(s, ctx.ctx, &cam, levels, &st);
      job.params.budget_ms = c.objects > 1000 ? 6.0f : 3.0f;
      ASSERT_TRUE(job.run());
      double tri = 0.0, vert = 0.0, lines = 0.0;
      size_t drawn = 0;
      for (size_t i = 0; i < levels.size(); ++i) {
        if (levels[i] < 0) continue;
        const uint32_t row = t.chain_level_offset[s.chains[i]] + static_cast<uint32_t>(levels[i]);
        tri += t.triangle_count[row];
        vert += t.vertex_count[row];
        lines += t.line_point_count[row];
        ++drawn;
      }
      EXPECT_GT(drawn, 0u) << "frame " << frame;
      EXPECT_EQ(st.drawn_count, drawn) << "frame " << frame;
      EXPECT_EQ(st.features.objects, static_cast<double>(drawn)) << "frame " << frame;
      EXPECT_EQ(st.features.triangles, tri) << "frame " << frame;
      EXPECT_EQ(st.features.vertices, vert) << "frame " << frame;
      EXPECT_EQ(st.features.line_points, lines) << "frame " << frame;
      const size_t slots = c.objects - st.culled_count;
      fewer_rows_than_slots += t.rowCount() <= slots ? 1 : 0;
    }
    // both write-out forms are covered
    if (c.objects > 1000) EXPECT_EQ(fewer_rows_than_slots, 8u);
    else EXPECT_EQ(fewer_rows_than_slots, 0u);
  }
}

// On warm frames along a smooth path most objects settle, and the settling pass writes their share
// of the frame's statistics (the write-out visits only the others): every statistic must still be
// what the levels out give, with must-draw objects and objects without benefit (importance 0) mixed
// in. The sums are compared exactly with the sums in object order (the write-out's order).
TEST(Selector, StatisticsOfWarmFramesAreTheSumsOverTheLevelsOut) {
  SyntheticScene s = makeScene(61, 2000, 6, 8, 120.0f, true);
  for (size_t i = 0; i < s.importance.size(); i += 7) s.importance[i] = 0.0f;
  for (size_t i = 3; i < s.must_draw.size(); i += 50) s.must_draw[i] = 1;
  const LevelTable t = s.table.view();
  Owned ctx(makeContext(2000, 64));
  const double per_frame = selectorCostModel(ctx.ctx).per_frame_ms;
  size_t warm = 0, with_dropped_zero_benefit = 0;
  for (int frame = 0; frame < 30; ++frame) {
    const Camera cam = makeCamera(glm::vec3(0.05f * frame, 1.0f, 20.0f - 0.2f * frame));
    std::vector<int8_t> levels;
    SelectionStats st;
    SelectionJob job = makeJob(s, ctx.ctx, &cam, levels, &st);
    job.params.budget_ms = 1.5f;
    job.params.calibrate = false;
    ASSERT_TRUE(job.run());
    double predicted = per_frame, benefit = 0.0, tri = 0.0, vert = 0.0, lines = 0.0;
    uint32_t drawn = 0, dropped = 0, culled = 0, not_drawn_without_benefit = 0;
    for (size_t i = 0; i < levels.size(); ++i) {
      double c0 = 0.0, b0 = 0.0;
      if (!selectorLastPoint(ctx.ctx, i, 0, &c0, &b0)) {
        ++culled;
        EXPECT_EQ(levels[i], -1) << "frame " << frame << " object " << i;
        continue;
      }
      if (levels[i] < 0) {
        EXPECT_EQ(s.must_draw[i], 0) << "frame " << frame << " object " << i;
        dropped += b0 > 0.0 ? 1u : 0u;
        not_drawn_without_benefit += b0 > 0.0 ? 0u : 1u;
        continue;
      }
      double c = 0.0, b = 0.0;
      ASSERT_TRUE(selectorLastPoint(ctx.ctx, i, levels[i], &c, &b));
      predicted += c;
      benefit += b;
      const uint32_t row = t.chain_level_offset[s.chains[i]] + static_cast<uint32_t>(levels[i]);
      tri += t.triangle_count[row];
      vert += t.vertex_count[row];
      lines += t.line_point_count[row];
      ++drawn;
    }
    EXPECT_EQ(st.culled_count, culled) << "frame " << frame;
    EXPECT_EQ(st.drawn_count, drawn) << "frame " << frame;
    EXPECT_EQ(st.dropped_count, dropped) << "frame " << frame;
    EXPECT_EQ(st.predicted_ms, predicted) << "frame " << frame;
    EXPECT_EQ(st.total_benefit, benefit) << "frame " << frame;
    EXPECT_EQ(st.features.objects, static_cast<double>(drawn)) << "frame " << frame;
    EXPECT_EQ(st.features.triangles, tri) << "frame " << frame;
    EXPECT_EQ(st.features.vertices, vert) << "frame " << frame;
    EXPECT_EQ(st.features.line_points, lines) << "frame " << frame;
    EXPECT_GT(dropped, 0u) << "the budget should bind, frame " << frame;
    warm += frame > 0 && st.switch_count * 10 < drawn ? 1 : 0;
    with_dropped_zero_benefit += not_drawn_without_benefit > 0 ? 1 : 0;
  }
  EXPECT_GT(warm, 20u) << "most frames should keep most levels (and settle most objects)";
  EXPECT_GT(with_dropped_zero_benefit, 20u) << "objects without benefit in view, not counted as dropped";
}

TEST(Selector, OutputsAreBitIdenticalForTheSameInputs) {
  SyntheticScene s = makeScene(8, 2000, 8, 8, 100.0f, true);
  Owned a(makeContext(2000, 100)), b(makeContext(2000, 100));
  for (int frame = 0; frame < 10; ++frame) {
    const Camera cam = makeCamera(glm::vec3(frame * 0.7f, 0.0f, 10.0f - frame * 3.0f));
    expectSameFrame(s, a.ctx, b.ctx, cam, SelectionMode::kBudget, 7.0f + frame, frame);
  }
}

// The AVX2 paths (where the CPU has them) and the SSE2 ones give the same bits, in both modes and
// along a path (incremental frames included); on a CPU without AVX2 both contexts run SSE2.
TEST(Selector, AvxAndSse2PathsGiveTheSameBits) {
  // 3005 objects: the last block of 64 ends in a group of fewer than 8 (the AVX2 compaction's tail)
  for (const size_t objects : {3000, 3005}) {
    SyntheticScene s = makeScene(12, objects, 8, 8, 100.0f, true);
    SelectorConfig cfg;
    cfg.max_object_count = objects;
    cfg.bracket_capacity = 100;
    Owned a(createSelectorContext(cfg));
    cfg.sse2_only = true;
    Owned b(createSelectorContext(cfg));
    for (int frame = 0; frame < 24; ++frame) {
      const Camera cam = makeCamera(glm::vec3(frame * 0.3f, 0.0f, 10.0f - frame * 0.5f));
      const SelectionMode mode = frame % 8 == 7 ? SelectionMode::kDistance : SelectionMode::kBudget;
      expectSameFrame(s, a.ctx, b.ctx, cam, mode, -1.0f, frame);
    }
  }
}

TEST(Selector, LargerBudgetNeverLowersBenefitFromColdStart) {
  for (uint32_t seed = 40; seed < 46; ++seed) {
    SyntheticScene s = makeScene(seed, 600, 5, 7, 80.0f);
    for (size_t i = 0; i < s.must_draw.size(); i += 50) s.must_draw[i] = 1;
    Owned o(makeContext(600, 32));
    const Camera cam = makeCamera(glm::vec3(0, 0, 10));
    for (bool stop : {true, false})
      for (BudgetAlgorithm alg : {BudgetAlgorithm::kGreedy, BudgetAlgorithm::kLagrangian}) {
        double last = -1.0;
        for (float budget = 0.2f; budget < 60.0f; budget *= 1.15f) {
          resetSelectorHistory(o.ctx);
          std::vector<int8_t> levels;
          SelectionStats st;
          SelectionJob job = makeJob(s, o.ctx, &cam, levels, &st);
          job.params.budget_ms = budget;
          job.params.algorithm = alg;
          job.params.stop_at_first_non_fitting = stop;
          ASSERT_TRUE(job.run());
          EXPECT_GE(st.total_benefit, last * (1.0 - 1e-6)) << "seed " << seed << " budget " << budget << " stop " << stop;
          last = st.total_benefit;
        }
      }
  }
}

namespace {

// Exact optimum of the multiple-choice knapsack by dynamic programming over objects, keeping the
// Pareto frontier of (cost, benefit) of partial solutions (exact for real-valued costs).
double exactOptimum(const std::vector<std::vector<std::pair<double, double>>>& options, double cap) {
  std::vector<std::pair<double, double>> front{{0.0, 0.0}};
  for (const auto& opts : options) {
    std::vector<std::pair<double, double>> next;
    for (const auto& p : front)
      for (const auto& o : opts)
        if (p.first + o.first <= cap) next.push_back({p.first + o.first, p.second + o.second});
    std::sort(next.begin(), next.end(), [](auto x, auto y) { return x.first != y.first ? x.first < y.first : x.second > y.second; });
    front.clear();
    for (const auto& p : next)
      if (front.empty() || p.second > front.back().second) front.push_back(p);
  }
  double best = 0.0;
  for (const auto& p : front) best = std::max(best, p.second);
  return best;
}

}  // namespace

TEST(Selector, GreedyIsWithinHalfOfTheExactOptimum) {
  double worst = 1.0, sum = 0.0, worst_plain = 1.0, sum_plain = 0.0, worst_skip = 1.0, sum_skip = 0.0;
  size_t instances = 0;
  for (uint32_t seed = 100; seed < 400; ++seed) {
    std::mt19937 rng(seed);
    const size_t objects = 3 + rng() % 6;
    SyntheticScene s = makeScene(seed, objects, 3, 2 + rng() % 5, 12.0f);
    for (size_t i = 0; i < objects; ++i)
      if (rng() % 5 == 0) s.must_draw[i] = 1;
    Owned o(makeContext(objects, 4));
    const Camera cam = makeCamera(glm::vec3(0, 0, 6));
    std::vector<int8_t> levels;
    SelectionStats st;
    SelectionJob job = makeJob(s, o.ctx, &cam, levels, &st);
    job.params.hysteresis = 0.0f;
    job.params.min_drop_px = 0.0f;  // the exact optimum below may drop any object
    // a budget that makes the instance tight: a fraction of drawing everything at level 0
    job.params.mode = SelectionMode::kDistance;
    ASSERT_TRUE(job.run());
    job.params.mode = SelectionMode::kBudget;
    job.params.budget_ms = 1e9f;
    resetSelectorHistory(o.ctx);
    ASSERT_TRUE(job.run());
    const double per_frame = selectorCostModel(o.ctx).per_frame_ms;
    job.params.budget_ms = static_cast<float>(per_frame + (st.predicted_ms - per_frame) * (0.1 + 0.8 * (rng() % 1000) / 1000.0));
    // every option of every object as the selector sees it this frame
    auto solve = [&](bool half, bool stop, double* opt) {
      resetSelectorHistory(o.ctx);
      job.params.half_approximation = half;
      job.params.stop_at_first_non_fitting = stop;
      EXPECT_TRUE(job.run());
      std::vector<std::vector<std::pair<double, double>>> options;
      double must_cost = 0.0;
      for (size_t i = 0; i < objects; ++i) {
        std::vector<std::pair<double, double>> opts;
        const int count = static_cast<int>(s.table.chain_level_offset[s.chains[i] + 1] - s.table.chain_level_offset[s.chains[i]]);
        double cost, benefit;
        if (!selectorLastPoint(o.ctx, i, -1, &cost, &benefit)) {
          opts.push_back({0.0, 0.0});  // culled
        } else {
          if (!s.must_draw[i]) opts.push_back({0.0, 0.0});
          for (int l = 0; l < count; ++l) {
            EXPECT_TRUE(selectorLastPoint(o.ctx, i, l, &cost, &benefit));
            opts.push_back({cost, benefit});
          }
        }
        options.push_back(opts);
        (void)must_cost;
      }
      *opt = exactOptimum(options, job.params.budget_ms - per_frame);
      return st;
    };
    double opt = 0.0;
    const SelectionStats full = solve(true, true, &opt);
    if (full.flags & kFlagOverBudget) continue;
    if (opt <= 0.0) continue;
    const SelectionStats plain = solve(false, true, &opt);
    const SelectionStats skip = solve(true, false, &opt);
    const double r = full.total_benefit / opt;
    EXPECT_LE(full.total_benefit, opt * (1.0 + 1e-6));  // the optimum is an upper bound
    EXPECT_GE(r, 0.5) << "seed " << seed;
    worst = std::min(worst, r);
    sum += r;
    worst_plain = std::min(worst_plain, plain.total_benefit / opt);
    sum_plain += plain.total_benefit / opt;
    worst_skip = std::min(worst_skip, skip.total_benefit / opt);
    sum_skip += skip.total_benefit / opt;
    ++instances;
  }
  ASSERT_GT(instances, 200u);
  std::printf("greedy/optimum over %zu instances: stop+half min %.4f mean %.4f | stop only min %.4f mean %.4f | "
              "skip+half min %.4f mean %.4f\n",
              instances, worst, sum / instances, worst_plain, sum_plain / instances, worst_skip, sum_skip / instances);
  RecordProperty("ratio_min", std::to_string(worst));
  RecordProperty("ratio_mean", std::to_string(sum / instances));
}

TEST(Selector, ReportFrameTimeFromAnotherThread) {
  // the engine's render thread reports frame times while the selecting thread runs; the mailbox is
  // a single atomic word, so this is data-race free by construction (run under TSAN in docs)
  SyntheticScene s = makeScene(12, 1000, 6, 8, 100.0f);
  Owned o(makeContext(1000, 64));
  std::atomic<uint64_t> published{0};
  std::atomic<uint64_t> acknowledged{0};
  std::atomic<bool> done{false};
  std::thread render([&] {
    uint64_t seen = 0;
    while (!done.load(std::memory_order_acquire)) {
      const uint64_t f = published.load(std::memory_order_acquire);
      if (f != seen) {
        seen = f;
        reportFrameTime(o.ctx, f - 1, 2.0f + 0.001f * static_cast<float>(f % 7));
        acknowledged.store(f, std::memory_order_release);
      } else {
        std::this_thread::yield();
      }
    }
  });
  SelectionStats st;
  for (int frame = 0; frame < 400; ++frame) {
    Camera cam = makeCamera(glm::vec3(0.0f, 0.0f, 10.0f - 0.05f * frame));
    std::vector<int8_t> levels;
    SelectionJob job = makeJob(s, o.ctx, &cam, levels, &st);
    job.params.budget_ms = 4.0f;
    ASSERT_TRUE(job.run());
    EXPECT_LE(st.predicted_ms, 4.0 * (1 + 1e-9));
    published.store(st.frame + 1, std::memory_order_release);
  }
  // however the threads were scheduled, the last frame's report reaches the context before one
  // more selection reads the mailbox (on a loaded machine the render thread may not have run at all
  // during the loop)
  const uint64_t last = published.load(std::memory_order_relaxed);
  while (acknowledged.load(std::memory_order_acquire) != last) std::this_thread::yield();
  {
    Camera cam = makeCamera(glm::vec3(0.0f, 0.0f, -10.0f));
    std::vector<int8_t> levels;
    SelectionJob job = makeJob(s, o.ctx, &cam, levels, &st);
    job.params.budget_ms = 4.0f;
    ASSERT_TRUE(job.run());
  }
  done.store(true, std::memory_order_release);
  render.join();
  const CostCoefficients c = selectorCostModel(o.ctx);
  EXPECT_GE(c.per_frame_ms, 0.0);
  EXPECT_GE(c.per_triangle_ms, 0.0);
  // the reports were used: the model moved from the prior toward the reported ~2 ms frames
  const CostCoefficients prior;
  EXPECT_NE(c.per_frame_ms, prior.per_frame_ms);
}

// The drop policy: under a budget far below what the view needs, every object in view with a
// projected radius of at least min_drop_px is drawn (at its cheapest level when nothing else fits)
// and only smaller ones are dropped; a hidden object may be dropped whatever its size; with the
// mandatory part above the budget the frame is flagged over budget; min_drop_px = 0 drops anything.
TEST(Selector, DropPolicyKeepsObjectsLargerThanMinDropPx) {
  SyntheticScene s = makeScene(11, 400, 5, 6, 120.0f);
  const size_t n = s.centers.size();
  const Camera cam = makeCamera(glm::vec3(0, 0, 5));
  const Frustum fr = computeFrustum(cam);
  auto radiusPx = [&](size_t i) {
    const float d = glm::length(s.centers[i] - cam.eye) - s.radii[i];
    return s.radii[i] / pixelSize(cam, std::max(d, cam.near_plane));
  };
  std::vector<float> visible(n, 1.0f);
  size_t hidden_large = n;
  for (size_t i = 0; i < n && hidden_large == n; ++i)
    if (sphereInFrustum(fr, s.centers[i], s.radii[i]) && radiusPx(i) > 20.0f) hidden_large = i;
  ASSERT_LT(hidden_large, n);
  visible[hidden_large] = 0.05f;
  for (const float min_drop : {4.0f, 10.0f, 0.0f}) {
    Owned o(makeContext(n));
    std::vector<int8_t> levels;
    SelectionStats st;
    SelectionJob job = makeJob(s, o.ctx, &cam, levels, &st);
    job.visible_fraction = Span<const float>(visible.data(), n);
    job.params.min_drop_px = min_drop;
    job.params.calibrate = false;
    const double per_frame = selectorCostModel(o.ctx).per_frame_ms;
    job.params.budget_ms = static_cast<float>(per_frame + 0.05);  // a small part of what the view needs
    for (int frame = 0; frame < 3; ++frame) {  // a cold frame, then warm ones (the settling pass)
      ASSERT_TRUE(job.run());
      size_t large = 0, dropped_large = 0, dropped_small = 0, coarsest = 0;
      for (size_t i = 0; i < n; ++i) {
        if (!sphereInFrustum(fr, s.centers[i], s.radii[i])) continue;
        const bool keep = min_drop > 0.0f && radiusPx(i) >= min_drop * 1.0001f && i != hidden_large;
        if (keep) {
          ++large;
          EXPECT_GE(levels[i], 0) << "object " << i << " at " << radiusPx(i) << " px, min_drop_px " << min_drop;
          const uint32_t b = s.table.chain_level_offset[s.chains[i]], e = s.table.chain_level_offset[s.chains[i] + 1];
          coarsest += levels[i] == static_cast<int>(e - b) - 1 ? 1 : 0;
        }
        if (levels[i] < 0) (keep ? dropped_large : dropped_small) += 1;
      }
      EXPECT_TRUE(min_drop == 0.0f || large > 20u) << large;
      EXPECT_EQ(dropped_large, 0u);
      if (min_drop > 0.0f) {
        EXPECT_GT(coarsest, large / 2);  // a tight budget: most kept objects at their cheapest level
        EXPECT_TRUE(st.flags & kFlagOverBudget);  // their cheapest levels alone exceed it
        EXPECT_GE(st.mandatory_ms, job.params.budget_ms);
        EXPECT_LT(levels[hidden_large], 0);  // hidden: dropped whatever its size
      } else {
        EXPECT_GT(dropped_small + dropped_large, 100u);
        EXPECT_FALSE(st.flags & kFlagOverBudget);
        EXPECT_LE(st.predicted_ms, job.params.budget_ms * 1.0001);
      }
    }
  }
  // bad input
  Owned o(makeContext(n));
  std::vector<int8_t> levels;
  SelectionJob job = makeJob(s, o.ctx, &cam, levels, nullptr);
  for (const float bad : {-1.0f, std::nanf(""), INFINITY}) {
    job.params.min_drop_px = bad;
    ASSERT_NE(job.error(), nullptr);
    EXPECT_NE(std::string(job.error()).find("min_drop_px"), std::string::npos);
  }
}

// With a budget that holds all kept objects at their cheapest levels and more, the warm frames (the
// settling pass, kept objects settling without their "not drawn" point) choose what a cold frame
// chooses from the same state: the greedy on full hulls.
TEST(Selector, DropPolicySettlingAgreesWithTheFullHullWalk) {
  SyntheticScene s = makeScene(5, 2000, 8, 6, 150.0f);
  const size_t n = s.centers.size();
  Owned warm(makeContext(n)), greedy(makeContext(n));
  size_t differ = 0, frames = 0;
  for (int f = 0; f < 40; ++f) {
    const Camera cam = makeCamera(glm::vec3(0.05f * f, 0.0f, 5.0f - 0.1f * f));
    std::vector<int8_t> a, b;
    SelectionStats sa, sb;
    SelectionJob ja = makeJob(s, warm.ctx, &cam, a, &sa);
    SelectionJob jb = makeJob(s, greedy.ctx, &cam, b, &sb);
    for (SelectionJob* j : {&ja, &jb}) {
      j->params.calibrate = false;
      j->params.budget_ms = 3.0f;
      j->params.hysteresis = 0.0f;  // last frame's level gets no bonus: the same problem every frame
    }
    jb.params.algorithm = BudgetAlgorithm::kGreedy;
    ASSERT_TRUE(ja.run());
    ASSERT_TRUE(jb.run());
    for (size_t i = 0; i < n; ++i) differ += a[i] != b[i] ? 1 : 0;
    ++frames;
    EXPECT_NEAR(sa.total_benefit, sb.total_benefit, 1e-4 * sb.total_benefit) << "frame " << f;
  }
  EXPECT_LT(differ, frames * n / 1000);  // ties at the budget's edge only
}
