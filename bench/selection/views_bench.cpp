// Selection with several views against one view in the same run, on the scene of selector_bench.cpp
// (selector_scene.h): 10k / 100k objects, smooth camera, budget mode at the same budget (half of
// what distance mode costs from the first camera).
//   BM_ViewsSingle: the one camera through the single-view path (SelectionJob::camera);
//   BM_ViewsStereoShadows: two eyes 64 mm apart in one group and two shadow cascades at X = 4 in
//   another (orthographic, looking down: a near cascade around the eye and a far one over the view);
//   BM_ViewsStereoShadowsDistance: the same in distance mode (the per-object pass alone).
// Counters: objects drawn and triangles per group (eyes, shadow) per frame, bytes per object, and
// from one distance-mode frame at the orbit's start with a primary camera and the two cascades:
// the triangles the primary view draws and those the cascades draw at X = 4 and at X = 1
// (deterministic, unlike the times).
// The target (issue 35): the four views within 2x the single view's time.
#include <benchmark/benchmark.h>

#include <glm/geometric.hpp>

#include "selection/selector_scene.h"

using namespace selection_bench;

namespace {

// A context with room for two view groups beside the scene's own.
struct ViewContext {
  SelectorContext* ctx = nullptr;
  explicit ViewContext(size_t n) {
    SelectorConfig cfg;
    cfg.max_object_count = n;
    cfg.max_levels_per_chain = 8;
    cfg.max_view_groups = 2;
    ctx = createSelectorContext(cfg);
  }
  ~ViewContext() { destroySelectorContext(ctx); }
};

View cascade(const glm::vec3& centre, float height) {
  View v;
  v.kind = ViewKind::kShadow;
  v.group = 1;
  v.pixels_per_cell = 4.0f;
  v.camera.projection = Projection::kOrthographic;
  v.camera.eye = centre + glm::vec3(0.0f, 500.0f, 0.0f);
  v.camera.target = centre;
  v.camera.up = glm::vec3(0.0f, 0.0f, -1.0f);
  v.camera.ortho_height = height;
  v.camera.near_plane = 1.0f;
  v.camera.far_plane = 1000.0f;
  v.camera.viewport_width_px = v.camera.viewport_height_px = 2048;
  return v;
}

// The four views of the frame at orbit time t.
void stereoShadowViews(size_t n, double t, View* views) {
  const Camera cam = cameraAt(n, t);
  const glm::vec3 fwd = glm::normalize(cam.target - cam.eye);
  const glm::vec3 right = glm::normalize(glm::cross(fwd, cam.up));
  for (int k = 0; k < 2; ++k) {
    const glm::vec3 offset = right * (k == 0 ? -0.032f : 0.032f);
    views[k].camera = cam;
    views[k].camera.eye += offset;
    views[k].camera.target += offset;
    views[k].kind = ViewKind::kEye;
    views[k].group = 0;
  }
  const float side = 10.0f * std::sqrt(static_cast<float>(n));
  views[2] = cascade(cam.eye + fwd * (0.05f * side), 0.1f * side);
  views[3] = cascade(cam.eye + fwd * (0.3f * side), 0.6f * side);
}

// Triangles drawn per group of one distance-mode frame at t = 0: the primary camera (group 0) and
// the two cascades at X = shadow_x (group 1).
void primaryAndShadowTriangles(BenchScene& s, SelectorContext* ctx, size_t n, float shadow_x, double* triangles) {
  View views[4];
  stereoShadowViews(n, 0.0, views);
  views[1] = views[2];
  views[2] = views[3];
  views[0].camera = cameraAt(n, 0.0);
  views[0].kind = ViewKind::kPrimary;
  views[1].pixels_per_cell = views[2].pixels_per_cell = shadow_x;
  std::vector<int8_t> group_levels(2 * n);
  SelectionJob j = job(s, nullptr, nullptr);
  j.params.mode = SelectionMode::kDistance;
  j.views = Span<const View>(views, 3);
  j.group_levels_out = Span<int8_t>(group_levels.data(), group_levels.size());
  j.context = ctx;
  j.run();
  resetSelectorHistory(ctx);
  for (size_t g = 0; g < 2; ++g) {
    triangles[g] = 0.0;
    for (size_t i = 0; i < n; ++i)
      if (group_levels[g * n + i] >= 0)
        triangles[g] += s.table.triangle_count[s.table.chain_level_offset[s.chains[i]] + group_levels[g * n + i]];
  }
}

void run(benchmark::State& state, bool views, bool distance = false) {
  const size_t n = static_cast<size_t>(state.range(0));
  BenchScene& s = scene(n);
  const float budget = budgetFor(s, n);
  ViewContext vc(n);
  double x4[2], x1[2];
  primaryAndShadowTriangles(s, vc.ctx, n, 4.0f, x4);
  primaryAndShadowTriangles(s, vc.ctx, n, 1.0f, x1);
  resetSelectorHistory(s.ctx);
  std::vector<int8_t> group_levels(2 * n);
  SelectionStats st;
  double t = 0.0, triangles[2] = {0.0, 0.0};
  size_t frames = 0, drawn = 0;
  View frame_views[4];
  for (auto _ : state) {
    t += 6.2831853 / 600.0;
    Camera cam = cameraAt(n, t);
    SelectionJob j = job(s, &cam, &st);
    j.params.budget_ms = budget;
    j.params.calibrate = false;
    if (distance) j.params.mode = SelectionMode::kDistance;
    if (views) {
      stereoShadowViews(n, t, frame_views);
      j.views = Span<const View>(frame_views, 4);
      j.group_levels_out = Span<int8_t>(group_levels.data(), group_levels.size());
      j.context = vc.ctx;
    }
    if (!j.run()) state.SkipWithError(j.error());
    benchmark::DoNotOptimize(s.levels.data());
    benchmark::ClobberMemory();
    ++frames;
    drawn += st.drawn_count;
    state.PauseTiming();
    for (size_t g = 0; g < (views ? 2u : 1u); ++g)
      for (size_t i = 0; i < n; ++i) {
        const int l = views ? group_levels[g * n + i] : s.levels[i];
        if (l >= 0) triangles[g] += s.table.triangle_count[s.table.chain_level_offset[s.chains[i]] + l];
      }
    state.ResumeTiming();
  }
  const double f = frames ? static_cast<double>(frames) : 1.0;
  state.SetItemsProcessed(static_cast<int64_t>(frames * n));
  state.counters["drawn"] = static_cast<double>(drawn) / f;
  state.counters["eye_triangles"] = triangles[0] / f;
  state.counters["shadow_triangles"] = triangles[1] / f;
  state.counters["bytes_per_object"] = selectorBytesPerObject(views ? vc.ctx : s.ctx);
  state.counters["primary_tris"] = x4[0];
  state.counters["shadow_tris_x4"] = x4[1];
  state.counters["shadow_tris_x1"] = x1[1];
}

void BM_ViewsSingle(benchmark::State& s) { run(s, false); }
void BM_ViewsStereoShadows(benchmark::State& s) { run(s, true); }
// The same four views in distance mode: the per-object pass (four frustum tests, the terms per
// group, the write-out) without the budget's tuple hulls and greedy: the floor of the budget frame
void BM_ViewsStereoShadowsDistance(benchmark::State& s) { run(s, true, true); }

}  // namespace

BENCHMARK(BM_ViewsSingle)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ViewsStereoShadows)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ViewsStereoShadowsDistance)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);
