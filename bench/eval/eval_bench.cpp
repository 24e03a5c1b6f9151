// Throughput of the evaluation instruments: Embree point queries (surface distance) and rays (image
// error). Both calls include building their two BVHs; the *Setup benchmarks measure that part alone
// (1 sample, 1-pixel views), so queries/s = items / (time - setup time) when setup matters.
#include <cmath>

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>

#include "eval/test_meshes.h"  // tests/: the generated meshes the eval tests use
#include "scenelod/eval/metrics.h"
#include "scenelod/eval/render.h"

namespace {

using scenelod::Mesh;

using scenelod::test::makeIcosphere;

const Mesh& fine() {
  static const Mesh m = makeIcosphere(6, 1.0f);  // 81,920 triangles, about the bunny's size
  return m;
}
const Mesh& coarse() {
  static const Mesh m = makeIcosphere(3, 1.0f);  // 1,280 triangles
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
