// Visibility benchmarks: occlusion rays per second on one core, the per-frame cost of the amortised
// occlusion estimate for 100 000 objects at 20 000 rays per frame, and the commit time after moving
// 10 000 objects. Scenes are synthetic: a jittered grid of icospheres (4 levels, 1280 to 20
// triangles) on a plane, seen from street level, so most rays meet other objects.
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "scenelod/selection/visibility.h"

using namespace scenelod;
using namespace scenelod::selection;

namespace {

// unit icosphere, `subdiv` times subdivided (20 * 4^subdiv triangles)
Mesh icosphere(int subdiv) {
  Mesh m;
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  const float v[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (const auto& p : v) m.positions.push_back(glm::normalize(glm::vec3(p[0], p[1], p[2])));
  m.triangles = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
                 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  for (int s = 0; s < subdiv; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.positions.push_back(glm::normalize(m.positions[a] + m.positions[b]));
      const uint32_t id = static_cast<uint32_t>(m.positions.size() - 1);
      mid.emplace(key, id);
      return id;
    };
    std::vector<uint32_t> out;
    for (size_t i = 0; i < m.triangles.size(); i += 3) {
      const uint32_t a = m.triangles[i], b = m.triangles[i + 1], c = m.triangles[i + 2];
      const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      out.insert(out.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    m.triangles = std::move(out);
  }
  return m;
}

const LodChain& sphereChain() {
  static const LodChain chain = [] {
    LodChain c;
    for (int s = 3; s >= 0; --s) {
      LodLevel l;
      l.mesh = icosphere(s);
      // distance of a face centre below the unit sphere, a bound on the level's deviation
      const float edge_angle = 1.1071487f / static_cast<float>(1 << s);
      l.max_error = 1.0f - std::cos(edge_angle * 0.6f);
      l.cell_width = edge_angle;
      c.levels.push_back(std::move(l));
    }
    c.levels[0].max_error = 0.0f;
    return c;
  }();
  return chain;
}

struct GridScene {
  std::vector<glm::mat4> world;
  std::vector<uint32_t> chain_ids;
  std::vector<int32_t> levels;
  Camera camera;
};

// n objects on a square grid with spacing 4, radius 0.5..1.5, seeded jitter
GridScene gridScene(size_t n) {
  GridScene g;
  std::mt19937 rng(12345);
  std::uniform_real_distribution<float> jitter(-1.0f, 1.0f), radius(0.5f, 1.5f);
  const size_t side = static_cast<size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  for (size_t i = 0; i < n; ++i) {
    const float x = 4.0f * static_cast<float>(i % side) + jitter(rng);
    const float z = -4.0f * static_cast<float>(i / side) + jitter(rng);
    const float r = radius(rng);
    g.world.push_back(glm::scale(glm::translate(glm::mat4(1.0f), {x, r, z}), glm::vec3(r)));
    g.chain_ids.push_back(0);
    g.levels.push_back(static_cast<int32_t>(i % 4));
  }
  const float extent = 4.0f * static_cast<float>(side);
  g.camera.eye = {-2.0f, 1.8f, 2.0f};
  g.camera.target = {extent * 0.5f, 0.5f, -extent * 0.5f};
  g.camera.far_plane = 1.0e5f;
  return g;
}

std::unique_ptr<RayScene> buildScene(const GridScene& g, const char* device_config = nullptr) {
  auto rs = std::make_unique<RayScene>();
  const LodChain* chains[] = {&sphereChain()};
  RaySceneParams p;
  p.device_config = device_config;
  if (!rs->init(Span<const LodChain* const>(chains, 1), p).ok() || !rs->setObjects(g.world, g.chain_ids, g.levels).ok()) return nullptr;
  rs->commit();
  return rs;
}

// One estimator frame at the given budget; items are occlusion samples.
void BM_OcclusionFrame(benchmark::State& state) {
  const size_t n = static_cast<size_t>(state.range(0));
  const GridScene g = gridScene(n);
  auto rs = buildScene(g);
  if (!rs) {
    state.SkipWithError("scene build failed");
    return;
  }
  OcclusionEstimator est;
  OcclusionParams p;
  p.ray_budget = static_cast<uint32_t>(state.range(1));
  est.init(n, p);
  std::vector<float> vis(n);
  uint64_t samples = 0, occlusion_rays = 0, self_hits = 0, tested = 0, occluder_candidates = 0;
  for (auto _ : state) {
    est.update(*rs, g.camera, Span<float>(vis));
    samples += est.lastStats().samples;
    occlusion_rays += est.lastStats().occlusion_rays;
    self_hits += est.lastStats().self_hits;
    tested += est.lastStats().objects_tested;
    occluder_candidates += est.lastStats().occluder_candidates;
    benchmark::DoNotOptimize(vis.data());
  }
  size_t hidden = 0;
  for (float v : vis) hidden += v < 0.05f ? 1 : 0;
  state.SetItemsProcessed(static_cast<int64_t>(samples));
  state.counters["occlusion_rays/s"] = benchmark::Counter(static_cast<double>(occlusion_rays), benchmark::Counter::kIsRate);
  state.counters["samples/s"] = benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
  state.counters["self_hit_share"] = samples ? static_cast<double>(self_hits) / static_cast<double>(samples) : 0.0;
  state.counters["objects_tested/frame"] =
      static_cast<double>(tested) / static_cast<double>(std::max<int64_t>(state.iterations(), 1));
  state.counters["candidates"] = est.lastStats().candidates;
  state.counters["occluders/test"] = tested ? static_cast<double>(occluder_candidates) / static_cast<double>(tested) : 0.0;
  state.counters["hidden_share_end"] = static_cast<double>(hidden) / static_cast<double>(n);
}
BENCHMARK(BM_OcclusionFrame)
    ->Args({10000, 20000})
    ->Args({100000, 20000})
    ->Args({100000, 0})
    ->Unit(benchmark::kMillisecond);

// Moves every object (a small translation) and commits; the device's build threads as given.
void commitMoving(benchmark::State& state, const char* device_config) {
  const size_t n = static_cast<size_t>(state.range(0));
  const GridScene g = gridScene(n);
  auto rs = buildScene(g, device_config);
  if (!rs) {
    state.SkipWithError("scene build failed");
    return;
  }
  float phase = 0.0f;
  for (auto _ : state) {
    phase += 0.01f;
    const glm::vec3 offset(0.1f * std::sin(phase), 0.0f, 0.1f * std::cos(phase));
    for (size_t i = 0; i < n; ++i)
      rs->setTransform(static_cast<uint32_t>(i), glm::translate(glm::mat4(1.0f), offset) * g.world[i]);
    rs->commit();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(n));
}
void BM_CommitMoving(benchmark::State& state) { commitMoving(state, nullptr); }
void BM_CommitMovingOneThread(benchmark::State& state) { commitMoving(state, "threads=1"); }
BENCHMARK(BM_CommitMoving)->Arg(10000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CommitMovingOneThread)->Arg(10000)->Unit(benchmark::kMillisecond)->UseRealTime();

// Picking one pixel per iteration, sweeping the screen.
void BM_Pick(benchmark::State& state) {
  const GridScene g = gridScene(static_cast<size_t>(state.range(0)));
  auto rs = buildScene(g);
  if (!rs) {
    state.SkipWithError("scene build failed");
    return;
  }
  uint32_t i = 0;
  for (auto _ : state) {
    const glm::vec2 px(static_cast<float>(i % 1280) + 0.5f, static_cast<float>((i / 1280) % 720) + 0.5f);
    benchmark::DoNotOptimize(rs->pick(g.camera, px));
    i += 7919;
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}
BENCHMARK(BM_Pick)->Arg(100000);

}  // namespace
