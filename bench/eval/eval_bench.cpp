// Throughput of the evaluation instruments: Embree point queries (surface distance) and rays (image
// error). Both calls include building their two BVHs; the *Setup benchmarks measure that part alone
// (1 sample, 1-pixel views), so queries/s = items / (time - setup time) when setup matters.
#include <cmath>
#include <map>
#include <utility>

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>

#include "scenelod/eval/metrics.h"
#include "scenelod/eval/render.h"

namespace {

using scenelod::Mesh;

// icosahedron subdivided `levels` times onto the unit sphere: 20 * 4^levels triangles
Mesh makeIcosphere(int levels) {
  const float t = (1.0f + std::sqrt(5.0f)) * 0.5f;
  std::vector<glm::vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p = glm::normalize(p);
  std::vector<uint32_t> f = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6,
                             7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7,
                             9, 8, 1};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto middle = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(glm::normalize(v[a] + v[b]));
      return mid[key] = static_cast<uint32_t>(v.size() - 1);
    };
    std::vector<uint32_t> g;
    for (size_t i = 0; i < f.size(); i += 3) {
      const uint32_t a = f[i], b = f[i + 1], c = f[i + 2];
      const uint32_t ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
      g.insert(g.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    f.swap(g);
  }
  Mesh m;
  m.positions = v;
  m.triangles = f;
  return m;
}

const Mesh& fine() {
  static const Mesh m = makeIcosphere(6);  // 81,920 triangles, about the bunny's size
  return m;
}
const Mesh& coarse() {
  static const Mesh m = makeIcosphere(3);  // 1,280 triangles
  return m;
}

void BM_SurfaceDistance(benchmark::State& state) {
  scenelod::eval::DistanceParams p;
  p.area_sample_count = static_cast<size_t>(state.range(0));
  scenelod::eval::DistanceResult r;
  for (auto _ : state) {
    scenelod::eval::measureSurfaceDistance(fine(), coarse(), p, r);
    benchmark::DoNotOptimize(r.hausdorff);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(r.forward.sample_count + r.backward.sample_count));
  state.counters["queries"] = static_cast<double>(r.forward.sample_count + r.backward.sample_count);
}
BENCHMARK(BM_SurfaceDistance)->Arg(1)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ImageError(benchmark::State& state) {
  scenelod::eval::ImageErrorParams p;
  p.resolution = static_cast<int>(state.range(0));
  scenelod::eval::ImageErrorResult r;
  for (auto _ : state) {
    scenelod::eval::measureImageError(fine(), coarse(), p, r);
    benchmark::DoNotOptimize(r.silhouette);
  }
  const int64_t rays = 2LL * scenelod::eval::kStandardViewCount * p.resolution * p.resolution;
  state.SetItemsProcessed(state.iterations() * rays);
  state.counters["rays"] = static_cast<double>(rays);
}
BENCHMARK(BM_ImageError)->Arg(1)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
