// SCROOGE (Reddy 1996) speed and reduction on the shared models and the bunny at sub-volumes of 1/64,
// 1/8 and 1 of the bounding volume (the paper's Table 1 setting, §8), plus a synthetic sphere that
// needs no files. Counters: input and output polygons and triangles, output vertices, the largest
// vertex move relative to the bounding-box diagonal. Real models run one iteration each (a run takes
// seconds); run with --benchmark_filter to pick models.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "lodcore/scrooge_models.h"
#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/scrooge.h"

namespace {

using namespace scenelod;

void runScrooge(benchmark::State& state, const Mesh& mesh, int divisions) {
  ScroogeParams p;
  const Aabb box = computeBounds(mesh);
  p.subvolume_size = scroogeSubvolumeForDivisions(box, divisions);
  Mesh out;
  ScroogeStats st;
  for (auto _ : state) {
    if (Error e = scroogeMesh(mesh, p, out, &st); !e.ok()) {
      state.SkipWithError(e.message.c_str());
      return;
    }
    benchmark::DoNotOptimize(out.triangles.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(mesh.triangleCount()));
  state.counters["in_polys"] = double(st.input_polygons);
  state.counters["in_tris"] = double(mesh.triangleCount());
  state.counters["polys"] = double(st.output_polygons);
  state.counters["tris"] = double(st.output_triangles);
  state.counters["verts"] = double(out.vertexCount());
  state.counters["max_move_rel"] = double(st.max_displacement) / double(box.diagonal());
}

Mesh sphere(int rings, int segments) {
  Mesh m;
  const float pi = 3.14159265f;
  m.positions.push_back({0, 0, 1});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const float th = pi * r / rings, ph = 2 * pi * s / segments;
      m.positions.push_back({std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)});
    }
  m.positions.push_back({0, 0, -1});
  const uint32_t south = uint32_t(m.positions.size() - 1);
  auto at = [&](int r, int s) { return uint32_t(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) m.triangles.insert(m.triangles.end(), {0, at(1, s), at(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.triangles.insert(m.triangles.end(), {at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      m.triangles.insert(m.triangles.end(), {at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) m.triangles.insert(m.triangles.end(), {south, at(rings - 1, s + 1), at(rings - 1, s)});
  return m;
}

void BM_ScroogeSphere(benchmark::State& state) {
  static const Mesh m = sphere(50, 100);  // 9,800 triangles
  runScrooge(state, m, int(state.range(0)));
}
BENCHMARK(BM_ScroogeSphere)->Arg(4)->Arg(2)->Arg(1)->Unit(benchmark::kMillisecond);

// floating-cell clustering (ClusterParams defaults) with the cell width of the sub-volume's longest edge
void runCluster(benchmark::State& state, const Mesh& mesh, int divisions) {
  const glm::vec3 s = scroogeSubvolumeForDivisions(computeBounds(mesh), divisions);
  ClusterParams cp;
  cp.cell_width = std::max({s.x, s.y, s.z});
  Mesh out;
  float max_error = 0.0f;
  for (auto _ : state) {
    if (Error e = clusterMesh(mesh, cp, out, &max_error); !e.ok()) {
      state.SkipWithError(e.message.c_str());
      return;
    }
    benchmark::DoNotOptimize(out.triangles.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(mesh.triangleCount()));
  state.counters["in_tris"] = double(mesh.triangleCount());
  state.counters["tris"] = double(out.triangleCount());
  state.counters["verts"] = double(out.vertexCount());
  state.counters["max_move_rel"] = double(max_error) / double(computeBounds(mesh).diagonal());
}

const char* fractionName(int divisions) { return divisions == 4 ? "1/64" : divisions == 2 ? "1/8" : "1"; }

struct RegisterModels {
  RegisterModels() {
    for (const std::string& name : bench::scroogeModelNames())
      for (int divisions : {4, 2, 1}) {
        benchmark::RegisterBenchmark(("BM_ClusterModel/" + name + "/" + fractionName(divisions)).c_str(),
                                     [name, divisions](benchmark::State& state) {
                                       std::string error;
                                       const Mesh* m = bench::loadModel(name, error);
                                       if (!m) {
                                         state.SkipWithError(("cannot read " + name + ": " + error).c_str());
                                         for (auto _ : state) {}
                                         return;
                                       }
                                       runCluster(state, *m, divisions);
                                     })
            ->Unit(benchmark::kMillisecond)
            ->Iterations(1);
        benchmark::RegisterBenchmark(("BM_ScroogeModel/" + name + "/" + fractionName(divisions)).c_str(),
                                     [name, divisions](benchmark::State& state) {
                                       std::string error;
                                       const Mesh* m = bench::loadModel(name, error);
                                       if (!m) {
                                         state.SkipWithError(("cannot read " + name + ": " + error).c_str());
                                         for (auto _ : state) {}
                                         return;
                                       }
                                       runScrooge(state, *m, divisions);
                                     })
            ->Unit(benchmark::kMillisecond)
            ->Iterations(1);
      }
  }
} register_models;

}  // namespace
