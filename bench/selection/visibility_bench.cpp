// Visibility benchmarks: occlusion rays per second on one core, the per-frame cost of the amortised
// occlusion estimate for 100 000 objects at 20 000 rays per frame, and the commit time after moving
// 10 000 objects. Scenes are synthetic: a jittered grid of icospheres (4 levels, 1280 to 20
// triangles) on a plane, seen from street level, so most rays meet other objects.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
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

// Thin occluders: a chain of a wall panel 8 wide, 4 high and 0.2 thick whose level 1 is its
// mid-plane (max_error 0.1, the thickness collapsed), so near the eye the estimator must trace the
// panels at level 0.
const LodChain& panelChain() {
  static const LodChain chain = [] {
    LodChain c;
    LodLevel l0, l1;
    const glm::vec3 lo(-4.0f, 0.0f, -0.1f), hi(4.0f, 4.0f, 0.1f);
    for (int i = 0; i < 8; ++i) l0.mesh.positions.push_back({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
    const uint32_t f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : f) l0.mesh.triangles.insert(l0.mesh.triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
    l1.mesh.positions = {{-4.0f, 0.0f, 0.0f}, {4.0f, 0.0f, 0.0f}, {4.0f, 4.0f, 0.0f}, {-4.0f, 4.0f, 0.0f}};
    l1.mesh.triangles = {0, 1, 2, 0, 2, 3};
    l1.max_error = 0.1f;
    c.levels.push_back(std::move(l0));
    c.levels.push_back(std::move(l1));
    return c;
  }();
  return chain;
}

// The grid scene with every other object a wall panel (chain 1), turned 0 or 90 degrees.
GridScene panelScene(size_t n) {
  GridScene g = gridScene(n);
  for (size_t i = 1; i < n; i += 2) {
    const glm::vec3 p(g.world[i][3]);
    g.world[i] = glm::rotate(glm::translate(glm::mat4(1.0f), {p.x, 0.0f, p.z}), (i / 2) % 2 ? 1.5707963f : 0.0f,
                             glm::vec3(0.0f, 1.0f, 0.0f));
    g.chain_ids[i] = 1;
    g.levels[i] = 0;
  }
  return g;
}

std::unique_ptr<RayScene> buildScene(const GridScene& g, const char* device_config = nullptr) {
  auto rs = std::make_unique<RayScene>();
  const LodChain* chains[] = {&sphereChain(), &panelChain()};
  RaySceneParams p;
  p.device_config = device_config;
  if (!rs->init(Span<const LodChain* const>(chains, 2), p).ok() || !rs->setObjects(g.world, g.chain_ids, g.levels).ok()) return nullptr;
  rs->commit();
  return rs;
}

// The grid seen from high above, looking down at its centre: few objects hide others.
GridScene openScene(size_t n) {
  GridScene g = gridScene(n);
  const float extent = 4.0f * std::ceil(std::sqrt(static_cast<float>(n)));
  g.camera.target = {extent * 0.5f, 0.0f, -extent * 0.5f};
  g.camera.eye = g.camera.target + glm::vec3(0.0f, extent * 0.9f, 0.01f * extent);
  return g;
}

enum class SceneKind { kStreet, kPanels, kOpen };
GridScene sceneOf(SceneKind kind, size_t n) {
  return kind == SceneKind::kPanels ? panelScene(n) : kind == SceneKind::kOpen ? openScene(n) : gridScene(n);
}

// The ray scene of `g` and `est` initialised for its objects at the benchmark's ray budget (range
// 1); null, with the benchmark skipped, when the scene cannot be built.
std::unique_ptr<RayScene> estimatorScene(benchmark::State& state, const GridScene& g, OcclusionEstimator& est) {
  auto rs = buildScene(g);
  if (!rs) {
    state.SkipWithError("scene build failed");
    return nullptr;
  }
  OcclusionParams p;
  p.ray_budget = static_cast<uint32_t>(state.range(1));
  est.init(g.world.size(), p);
  return rs;
}

// One estimator frame at the given budget; items are occlusion samples.
void occlusionFrame(benchmark::State& state, SceneKind kind) {
  const size_t n = static_cast<size_t>(state.range(0));
  const GridScene g = sceneOf(kind, n);
  OcclusionEstimator est;
  auto rs = estimatorScene(state, g, est);
  if (!rs) return;
  std::vector<float> vis(n);
  uint64_t samples = 0, occlusion_rays = 0, self_hits = 0, tested = 0, occluder_candidates = 0, embree_rays = 0;
  uint64_t hidden_samples = 0;
  for (auto _ : state) {
    est.update(*rs, g.camera, Span<float>(vis));
    samples += est.lastStats().samples;
    embree_rays += est.lastStats().embree_rays;
    hidden_samples += est.lastStats().hidden_samples;
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
  state.counters["rays/sample"] = samples ? static_cast<double>(embree_rays) / static_cast<double>(samples) : 0.0;
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(embree_rays), benchmark::Counter::kIsRate);
  state.counters["hidden_sample_share"] = self_hits ? static_cast<double>(hidden_samples) / static_cast<double>(self_hits) : 0.0;
}
void BM_OcclusionFrame(benchmark::State& state) { occlusionFrame(state, SceneKind::kStreet); }
// half the objects thin wall panels (panelChain)
void BM_OcclusionFramePanels(benchmark::State& state) { occlusionFrame(state, SceneKind::kPanels); }
// seen from above: most samples visible, so most tests trace the object itself too
void BM_OcclusionFrameOpen(benchmark::State& state) { occlusionFrame(state, SceneKind::kOpen); }
BENCHMARK(BM_OcclusionFramePanels)->Args({10000, 20000})->Args({100000, 20000})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OcclusionFrameOpen)->Args({100000, 20000})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OcclusionFrame)
    ->Args({10000, 20000})
    ->Args({100000, 20000})
    ->Args({100000, 0})
    ->Unit(benchmark::kMillisecond);

// The floor: the same question asked of Embree alone. The objects the estimator tests in one frame
// (after 8 warm-up frames, as its benchmark runs), 16 rays each through the same golden-angle disc
// over each object's sphere footprint, each ray stopping just before the object's bounding sphere,
// traced by a plain loop of rtcOccluded1 against one Embree scene holding every object as an
// instance of its occluder level. One ray per sample; items are rays.
void occlusionFloor(benchmark::State& state, SceneKind kind) {
  const size_t n = static_cast<size_t>(state.range(0));
  const GridScene g = sceneOf(kind, n);
  OcclusionEstimator est;
  auto rs = estimatorScene(state, g, est);
  if (!rs) return;
  const OcclusionParams p;  // the estimator's rays per test (estimatorScene changes only the budget)
  for (int f = 0; f < 8; ++f) est.update(*rs, g.camera, {});
  const uint32_t occluder_level = static_cast<uint32_t>(rs->occluderLevel(0));

  RTCDevice device = rtcNewDevice("threads=1");
  RTCScene proto = rtcNewScene(device);
  {
    const Mesh& mesh = sphereChain().levels[occluder_level].mesh;
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), mesh.vertexCount()));
    auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(uint32_t), mesh.triangleCount()));
    for (size_t i = 0; i < mesh.vertexCount(); ++i) {
      v[3 * i] = mesh.positions[i].x;
      v[3 * i + 1] = mesh.positions[i].y;
      v[3 * i + 2] = mesh.positions[i].z;
    }
    std::copy(mesh.triangles.begin(), mesh.triangles.end(), t);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(proto, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(proto);
  }
  RTCScene top = rtcNewScene(device);
  for (size_t i = 0; i < n; ++i) {
    RTCGeometry inst = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(inst, proto);
    rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, &g.world[i][0][0]);
    rtcCommitGeometry(inst);
    rtcAttachGeometry(top, inst);
    rtcReleaseGeometry(inst);
  }
  rtcCommitScene(top);

  // the rays of the objects tested in the last frame
  struct FloorRay {
    glm::vec3 o, d;
    float t_far;
  };
  std::vector<FloorRay> rays;
  const Span<const glm::vec4> spheres = rs->worldSpheres();
  const float golden = 2.39996323f;
  const glm::vec3 eye = g.camera.eye;
  const glm::vec3 view_forward = glm::normalize(g.camera.target - eye);
  const glm::vec3 view_right = glm::normalize(glm::cross(view_forward, g.camera.up));
  const glm::vec3 view_up = glm::cross(view_right, view_forward);
  for (size_t id = 0; id < n; ++id) {
    if (est.ageFrames(*rs, static_cast<uint32_t>(id)) != 0) continue;
    const glm::vec3 c(spheres[id]);
    const float r = spheres[id].w;
    const float dist = glm::length(c - eye);
    if (dist <= r) continue;
    const glm::vec3 w = (c - eye) / dist;
    const float disc_r = r * dist / std::sqrt(dist * dist - r * r);
    // the estimator's disc axes: across the view direction, from the up vector unless nearly parallel
    const glm::vec3 ref = std::fabs(glm::dot(w, view_up)) < 0.9f ? view_up : view_right;
    const glm::vec3 u = glm::normalize(glm::cross(w, ref)), v = glm::cross(u, w);
    for (uint32_t k = 0; k < p.rays_per_test; ++k) {
      const float rad = std::sqrt((static_cast<float>(k) + 0.5f) / static_cast<float>(p.rays_per_test));
      const float th = static_cast<float>(k) * golden;
      const glm::vec3 target = c + disc_r * rad * (std::cos(th) * u + std::sin(th) * v);
      const glm::vec3 d = glm::normalize(target - eye);
      // stop before the object's bounding sphere (or its closest approach, for a grazing ray)
      // (the squared miss distance from a cross product: |c - eye|^2 - along^2 cancels at 1,000 units)
      const float along = glm::dot(c - eye, d);
      const glm::vec3 across = glm::cross(c - eye, d);
      const float miss2 = glm::dot(across, across);
      const float t_far = miss2 < r * r ? along - std::sqrt(r * r - miss2) : along;
      rays.push_back({eye, d, t_far * (1.0f - 1e-4f)});
    }
  }
  uint64_t traced = 0, hidden = 0;
  for (auto _ : state) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (const FloorRay& fr : rays) {
      RTCRay r;
      r.org_x = fr.o.x;
      r.org_y = fr.o.y;
      r.org_z = fr.o.z;
      r.dir_x = fr.d.x;
      r.dir_y = fr.d.y;
      r.dir_z = fr.d.z;
      r.tnear = g.camera.near_plane;
      r.tfar = fr.t_far;
      r.time = 0.0f;
      r.mask = 0xFFFFFFFFu;
      r.id = 0;
      r.flags = 0;
      rtcOccluded1(top, &ctx, &r);
      hidden += r.tfar < 0.0f ? 1 : 0;
    }
    traced += rays.size();
  }
  rtcReleaseScene(top);
  rtcReleaseScene(proto);
  rtcReleaseDevice(device);
  state.SetItemsProcessed(static_cast<int64_t>(traced));
  state.counters["rays/sample"] = 1.0;
  state.counters["rays/frame"] = static_cast<double>(rays.size());
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(traced), benchmark::Counter::kIsRate);
  state.counters["hidden_sample_share"] = traced ? static_cast<double>(hidden) / static_cast<double>(traced) : 0.0;
}
void BM_OcclusionFloor(benchmark::State& state) { occlusionFloor(state, SceneKind::kStreet); }
void BM_OcclusionFloorOpen(benchmark::State& state) { occlusionFloor(state, SceneKind::kOpen); }
BENCHMARK(BM_OcclusionFloor)->Args({10000, 20000})->Args({100000, 20000})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OcclusionFloorOpen)->Args({100000, 20000})->Unit(benchmark::kMillisecond);

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
