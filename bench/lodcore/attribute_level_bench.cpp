// Clustering levels with and without attributes (docs/CLUSTERING.md, "Attributes"): the same level
// of the same mesh built once with its texture coordinates (tangents, triangle groups) and once
// stripped of them, so that the attribute pass's cost reads as a ratio (target <= 1.5); and the peak
// memory of an 8-level chain with attributes against 64 B per input vertex + 16 B per triangle + the
// attributes' own bytes (texture coordinates, tangents, skin, triangle groups).
//   (cd build/dev && bench/scenelod_lodcore_bench --benchmark_filter=Attribute)
// (the Duck from ../shared/models beside the checkout, or $SCENELOD_SHARED_MODELS)
#include <cmath>
#include <map>
#include <string>

#include <benchmark/benchmark.h>

#include "alloc_counting.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/cluster.h"
#include "scrooge_models.h"

using namespace scenelod;

namespace {

// A UV sphere of about 200 k triangles as a textured asset has it: texture coordinates from
// longitude and latitude (the vertices of longitude 0 repeated with u = 1, a UV seam), tangents along
// the longitude (sign +1), triangles in two groups (the northern and southern hemispheres).
Mesh texturedSphere() {
  const int rings = 250, segments = 400;
  const float pi = 3.14159265358979f;
  Mesh m;
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s <= segments; ++s) {
      const float th = pi * float(r) / float(rings), ph = 2.0f * pi * float(s) / float(segments);
      const glm::vec3 n(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      m.positions.push_back(n);
      m.normals.push_back(n);
      m.uvs.emplace_back(float(s) / float(segments), float(r) / float(rings));
      m.tangents.emplace_back(-std::sin(ph), std::cos(ph), 0.0f, 1.0f);
    }
  const uint32_t row = uint32_t(segments + 1);
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const uint32_t a = uint32_t(r) * row + uint32_t(s), b = a + 1, c = a + row + 1, d = a + row;
      const uint32_t group = r < rings / 2 ? 0u : 1u;
      if (r > 0) m.triangles.insert(m.triangles.end(), {a, d, b}), m.triangle_groups.push_back(group);
      if (r + 1 < rings) m.triangles.insert(m.triangles.end(), {b, d, c}), m.triangle_groups.push_back(group);
    }
  return m;
}

// the mesh without its attributes: positions, normals, colours and primitives only
Mesh stripped(const Mesh& m) {
  Mesh s;
  s.positions = m.positions;
  s.normals = m.normals;
  s.colors = m.colors;
  s.triangles = m.triangles;
  s.edges = m.edges;
  s.edge_thickness = m.edge_thickness;
  s.points = m.points;
  return s;
}

// the benchmarks' meshes: 0 the textured sphere, 1 the Duck (when the shared models are present)
const Mesh* attributeMesh(int which, bool with_attributes, std::string& error) {
  static std::map<std::pair<int, bool>, Mesh> cache;
  auto it = cache.find({which, with_attributes});
  if (it != cache.end()) return &it->second;
  Mesh full;
  if (which == 0) {
    full = texturedSphere();
  } else {
    const Mesh* duck = bench::loadModel("Duck", error);
    if (!duck) return nullptr;
    full = *duck;
  }
  return &(cache[{which, with_attributes}] = with_attributes ? full : stripped(full));
}

const char* meshName(int which) { return which == 0 ? "UV sphere 200k" : "Duck"; }

// One level at a width that keeps about `percent` % of the stripped mesh's triangles, the same width
// with and without attributes. The time is the level's own (ChainStats::level_seconds of a one-level
// chain): the welding, charts and grading are once per mesh for a chain, reported apart as prepare_ms.
// Args: mesh (0 sphere, 1 Duck), attributes (0 stripped, 1 kept), percent.
void BM_AttributeLevel(benchmark::State& state) {
  const int which = int(state.range(0));
  const bool with = state.range(1) == 1;
  std::string error;
  const Mesh* m = attributeMesh(which, with, error);
  const Mesh* plain = attributeMesh(which, false, error);
  if (!m || !plain) {
    state.SkipWithError(error.c_str());
    return;
  }
  ChainParams cp;
  cp.level_count = 1;
  if (Error e = findCellWidthForTarget(*plain, cp.cluster, plain->triangleCount() * size_t(state.range(2)) / 100,
                                       cp.first_cell_width);
      !e.ok()) {
    state.SkipWithError(e.message.c_str());
    return;
  }
  ChainStats stats;
  LodChain chain;
  for (auto _ : state) {
    if (Error e = buildChain(*m, cp, chain, &stats); !e.ok()) {
      state.SkipWithError(e.message.c_str());
      break;
    }
    state.SetIterationTime(stats.level_seconds[0]);
  }
  if (chain.levels.size() < 2) return;  // (an error was reported)
  state.counters["prepare_ms"] = stats.prepare_seconds * 1e3;
  state.counters["level_triangles"] = double(chain.levels[1].mesh.triangleCount());
  state.counters["level_vertices"] = double(chain.levels[1].mesh.vertexCount());
  state.SetLabel(std::string(meshName(which)) + (with ? ", attributes" : ", stripped"));
}
BENCHMARK(BM_AttributeLevel)
    ->ArgsProduct({{0, 1}, {0, 1}, {50, 10}})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

// the bytes of a mesh's attributes beyond positions, normals, colours and primitives
double attributeBytes(const Mesh& m) {
  double bytes = double(m.uvs.size()) * sizeof(glm::vec2) + double(m.tangents.size()) * sizeof(glm::vec4) +
                 double(m.joints.size()) * sizeof(glm::u16vec4) + double(m.weights.size()) * sizeof(glm::vec4) +
                 double(m.triangle_groups.size()) * sizeof(uint32_t) + double(m.joint_parents.size()) * sizeof(int32_t);
  for (const std::vector<glm::vec2>& set : m.extra_uvs) bytes += double(set.size()) * sizeof(glm::vec2);
  return bytes;
}

// Peak extra memory (operator new, counted by cluster_bench.cpp) while building an 8-level chain,
// against the budget 64 B per input vertex + 16 B per triangle + the attributes' own bytes. Args:
// mesh, attributes (0 stripped, 1 kept), hand-over (0: the mesh copied into level 0, as
// buildChain(const Mesh&) does; 1: the engine's own copy, made before the baseline, moved in with
// buildChain(Mesh&&), so level 0 costs nothing extra).
void BM_AttributeChainMemory(benchmark::State& state) {
  const int which = int(state.range(0));
  const bool with = state.range(1) == 1, hand_over = state.range(2) == 1;
  std::string error;
  const Mesh* m = attributeMesh(which, with, error);
  if (!m) {
    state.SkipWithError(error.c_str());
    return;
  }
  long long peak_extra = 0, retained = 0;
  for (auto _ : state) {
    LodChain chain;
    ChainParams cp;
    cp.level_count = 8;
    Mesh own = hand_over ? *m : Mesh();
    const long long base = bench::resetAllocationPeak();
    if (Error e = hand_over ? buildChain(std::move(own), cp, chain) : buildChain(*m, cp, chain); !e.ok()) {
      state.SkipWithError(e.message.c_str());
      break;
    }
    peak_extra = bench::allocationPeak() - base;
    retained = bench::allocatedBytes() - base;
    benchmark::DoNotOptimize(chain.levels.data());
  }
  const double budget = 64.0 * double(m->vertexCount()) + 16.0 * double(m->triangleCount()) + attributeBytes(*m);
  state.counters["peak_MB"] = double(peak_extra) / 1e6;
  state.counters["retained_MB"] = double(retained) / 1e6;
  state.counters["budget_MB"] = budget / 1e6;
  state.counters["peak_over_budget"] = double(peak_extra) / budget;
  state.SetLabel(std::string(meshName(which)) + (with ? ", attributes" : ", stripped") +
                 (hand_over ? ", handed over" : ", copied"));
}
BENCHMARK(BM_AttributeChainMemory)
    ->ArgsProduct({{0, 1}, {0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace
