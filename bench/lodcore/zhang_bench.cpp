// Zhang, Shu & Luo 2003 vision-characteristic edge collapse against meshopt_simplify at the same
// triangle counts: the paper's Table 1 rates on the bunny, time against decimation rate (the paper's
// Fig. 9) and against mesh size (generated bumpy tori, 10 k to 1 M triangles).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <meshoptimizer.h>

#include "scenelod/lodcore/obj_io.h"
#include "scenelod/lodcore/zhang.h"

using namespace scenelod;

namespace {

const Mesh& bunny() {
  static const Mesh m = [] {
    Mesh b;
    if (!readObj(SCENELOD_BUNNY_PATH, b).ok()) b = Mesh{};  // absent: the bunny benchmarks skip
    return b;
  }();
  return m;
}

// a torus with ripples: nu x nv quads, 2 nu nv triangles, closed, curved everywhere
Mesh bumpyTorus(int nu, int nv) {
  Mesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const float u = 6.2831853f * i / nu, v = 6.2831853f * j / nv;
      const float r = 0.35f + 0.03f * std::sin(7 * u) * std::sin(5 * v);
      m.positions.push_back({(1.0f + r * std::cos(v)) * std::cos(u), (1.0f + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const uint32_t a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv,
                     d = i * nv + (j + 1) % nv;
      m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
    }
  return m;
}

const Mesh& torusOfSize(int64_t triangles) {
  static std::vector<std::pair<int64_t, Mesh>> cache;
  for (auto& c : cache)
    if (c.first == triangles) return c.second;
  const int nv = static_cast<int>(std::sqrt(triangles / 4.0));
  cache.emplace_back(triangles, bumpyTorus(static_cast<int>(triangles / (2 * nv)), nv));
  return cache.back().second;
}

void runZhang(benchmark::State& state, const Mesh& in, size_t target, ZhangMode mode,
              ZhangPlacement placement = ZhangPlacement::kInterpolated) {
  if (in.triangles.empty()) {
    state.SkipWithError("bunny not found");
    return;
  }
  ZhangParams p;
  p.mode = mode;
  p.placement = placement;
  Mesh out;
  ZhangStats st;
  for (auto _ : state) {
    const Error e = simplifyZhang(in, target, p, out, &st);
    if (!e.ok()) state.SkipWithError(e.message.c_str());
    benchmark::DoNotOptimize(out.triangles.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(in.triangleCount()));
  state.counters["in_tris"] = static_cast<double>(in.triangleCount());
  state.counters["out_tris"] = static_cast<double>(out.triangleCount());
  state.counters["out_verts"] = static_cast<double>(out.vertexCount());
  state.counters["max_disp_rel"] = st.max_displacement / computeBounds(in).diagonal();
}

void runMeshopt(benchmark::State& state, const Mesh& in, size_t target) {
  if (in.triangles.empty()) {
    state.SkipWithError("bunny not found");
    return;
  }
  std::vector<unsigned int> out(in.triangles.size());
  size_t n = 0;
  float err = 0.0f;
  for (auto _ : state) {
    n = meshopt_simplify(out.data(), in.triangles.data(), in.triangles.size(), &in.positions[0].x,
                         in.positions.size(), sizeof(glm::vec3), 3 * target, 1.0f, 0, &err);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(in.triangleCount()));
  state.counters["in_tris"] = static_cast<double>(in.triangleCount());
  state.counters["out_tris"] = static_cast<double>(n / 3);
  state.counters["meshopt_err_rel"] = err;
}

size_t targetForRate(const Mesh& m, int64_t rate_percent) {
  return static_cast<size_t>(std::llround(m.triangleCount() * (100 - rate_percent) / 100.0));
}

// Table 1 rates and Fig. 9's sweep: Arg is the decimation rate in percent
// second Arg: 0 = the paper's CA-interpolated placement, 1 = onto the chosen neighbour
void BM_ZhangBunny(benchmark::State& s) {
  runZhang(s, bunny(), targetForRate(bunny(), s.range(0)), ZhangMode::kEdgeCollapse,
           s.range(1) ? ZhangPlacement::kNeighbour : ZhangPlacement::kInterpolated);
}
void BM_ZhangTriangleBunny(benchmark::State& s) {
  runZhang(s, bunny(), targetForRate(bunny(), s.range(0)), ZhangMode::kTriangleDecimation);
}
void BM_MeshoptBunny(benchmark::State& s) { runMeshopt(s, bunny(), targetForRate(bunny(), s.range(0))); }
// mesh size at 90 %: Arg is the input triangle count
void BM_ZhangSize(benchmark::State& s) {
  const Mesh& m = torusOfSize(s.range(0));
  runZhang(s, m, targetForRate(m, 90), ZhangMode::kEdgeCollapse);
}
void BM_MeshoptSize(benchmark::State& s) {
  const Mesh& m = torusOfSize(s.range(0));
  runMeshopt(s, m, targetForRate(m, 90));
}

BENCHMARK(BM_ZhangBunny)
    ->ArgsProduct({{10, 30, 50, 70, 80, 90, 95}, {0}})
    ->ArgsProduct({{50, 80, 90, 95}, {1}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MeshoptBunny)->Arg(50)->Arg(80)->Arg(90)->Arg(95)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ZhangTriangleBunny)->Arg(50)->Arg(80)->Arg(90)->Arg(95)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ZhangSize)->Arg(10000)->Arg(100000)->Arg(300000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MeshoptSize)->Arg(10000)->Arg(100000)->Arg(300000)->Arg(1000000)->Unit(benchmark::kMillisecond);

}  // namespace
