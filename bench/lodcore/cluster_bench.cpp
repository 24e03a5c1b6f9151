// Vertex clustering (Low & Tan 1997 floating cells; Rossignac & Borrel uniform grid) against
// meshoptimizer's meshopt_simplifySloppy and meshopt_simplify, in the same process on the same mesh.
// Peak extra memory is measured by counting every operator new/delete of this program.
#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <vector>

#include <benchmark/benchmark.h>
#include <meshoptimizer.h>
#include <tbb/global_control.h>

#include "alloc_counting.h"
#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/obj_io.h"

// ---- allocation counting (current and peak bytes through operator new) ----
namespace {
std::atomic<long long> g_current{0};
std::atomic<long long> g_peak{0};

void noteAlloc(void* p) {
  if (!p) return;
  const long long now = g_current.fetch_add(static_cast<long long>(malloc_usable_size(p))) +
                        static_cast<long long>(malloc_usable_size(p));
  long long peak = g_peak.load();
  while (now > peak && !g_peak.compare_exchange_weak(peak, now)) {
  }
}
void noteFree(void* p) {
  if (p) g_current.fetch_sub(static_cast<long long>(malloc_usable_size(p)));
}
void* countedAlloc(size_t n) {
  void* p = std::malloc(n ? n : 1);
  if (!p) throw std::bad_alloc();
  noteAlloc(p);
  return p;
}
void* countedAlignedAlloc(size_t n, std::align_val_t al) {
  void* p = nullptr;
  if (posix_memalign(&p, static_cast<size_t>(al), n ? n : 1) != 0) throw std::bad_alloc();
  noteAlloc(p);
  return p;
}
void countedFree(void* p) {
  noteFree(p);
  std::free(p);
}
}  // namespace

void* operator new(size_t n) { return countedAlloc(n); }
void* operator new[](size_t n) { return countedAlloc(n); }
void* operator new(size_t n, std::align_val_t al) { return countedAlignedAlloc(n, al); }
void* operator new[](size_t n, std::align_val_t al) { return countedAlignedAlloc(n, al); }
void operator delete(void* p) noexcept { countedFree(p); }
void operator delete[](void* p) noexcept { countedFree(p); }
void operator delete(void* p, size_t) noexcept { countedFree(p); }
void operator delete[](void* p, size_t) noexcept { countedFree(p); }
void operator delete(void* p, std::align_val_t) noexcept { countedFree(p); }
void operator delete[](void* p, std::align_val_t) noexcept { countedFree(p); }
void operator delete(void* p, size_t, std::align_val_t) noexcept { countedFree(p); }
void operator delete[](void* p, size_t, std::align_val_t) noexcept { countedFree(p); }

// (alloc_counting.h: the counters for the program's other benchmarks)
long long scenelod::bench::allocatedBytes() { return g_current.load(); }
long long scenelod::bench::resetAllocationPeak() {
  const long long now = g_current.load();
  g_peak.store(now);
  return now;
}
long long scenelod::bench::allocationPeak() { return g_peak.load(); }

using namespace scenelod;

namespace {

const Mesh& bunny() {
  static Mesh m = [] {
    Mesh b;
    if (Error e = readObj(SCENELOD_BUNNY_PATH, b); !e.ok()) {
      std::fprintf(stderr, "cluster_bench: %s\n", e.message.c_str());
      std::exit(1);
    }
    return b;
  }();
  return m;
}

const Mesh& bigMesh() {
  static Mesh m = test::makeBumpySphere(720, 720);  // 1,035,360 triangles
  return m;
}

// the "meshes of 10 M triangles must not exhaust memory": one closed surface of 10,003,864
// triangles, and 10,000,000 triangles in 8,000 separate spheres of 1,250 triangles on a 20 x 20 x 20
// lattice of spacing 10 (a box 190 wide around parts of diameter 1: the cells of the fine levels
// spread over many bricks of a box mostly empty: the fine levels take the hash, whose memory the
// bricks and their table would pass)
const Mesh& hugeSphere() {
  static Mesh m = test::makeBumpySphere(2237, 2237);
  return m;
}
const Mesh& hugeScattered() {
  static Mesh m = [] {
    const Mesh part = test::makeSphere({0, 0, 0}, 0.5f, 26, 25);
    Mesh all;
    all.positions.reserve(part.positions.size() * 8000);
    all.triangles.reserve(part.triangles.size() * 8000);
    for (int z = 0; z < 20; ++z)
      for (int y = 0; y < 20; ++y)
        for (int x = 0; x < 20; ++x) {
          Mesh moved = part;
          for (glm::vec3& v : moved.positions) v += glm::vec3(10.0f * float(x), 10.0f * float(y), 10.0f * float(z));
          test::appendMesh(all, moved);
        }
    return all;
  }();
  return m;
}

struct Prepared {
  PreparedMesh p;
  ClusterParams params;
  size_t triangles = 0;
};

// a prepared mesh and the cell width that keeps about `fraction` of its triangles
Prepared& prepared(const Mesh& m, double fraction, ClusterParams params = ClusterParams()) {
  static std::vector<std::pair<std::pair<const Mesh*, double>, Prepared*>> cache;
  for (auto& c : cache)
    if (c.first.first == &m && c.first.second == fraction && c.second->params.method == params.method)
      return *c.second;
  Prepared* pr = new Prepared;
  pr->params = params;
  prepareMesh(m, params, pr->p);
  findCellWidthForTarget(pr->p, params, size_t(double(m.triangleCount()) * fraction), pr->params.cell_width, 0.01);
  Mesh out;
  clusterPrepared(pr->p, pr->params, out);
  pr->triangles = out.triangleCount();
  cache.push_back({{&m, fraction}, pr});
  return *pr;
}

void reportTriangles(benchmark::State& state, const Mesh& in, size_t out_triangles) {
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(in.triangleCount()));
  state.counters["in_tris"] = double(in.triangleCount());
  state.counters["out_tris"] = double(out_triangles);
}

// The minimum over repetitions, beside Google Benchmark's mean and median: on a shared machine
// other tenants only ever add time, so the fastest repetition is the least disturbed one
// (docs/bench/targets.md quotes it where the medians scatter). For rate counters such as
// items_per_second the min row holds the smallest rate: read its time columns.
double minimumOf(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end()); }
// every benchmark of this file registered with the min statistic
#define SCENELOD_BENCHMARK(fn) BENCHMARK(fn)->ComputeStatistics("min", minimumOf)

// one level of `m` (prepared once) at the width keeping Arg % of its triangles, timed alone
void levelAtArg(benchmark::State& state, const Mesh& m, LodMethod method) {
  ClusterParams params;
  params.method = method;
  Prepared& pr = prepared(m, double(state.range(0)) / 100.0, params);
  Mesh out;
  for (auto _ : state) {
    clusterPrepared(pr.p, pr.params, out);
    benchmark::DoNotOptimize(out.triangles.data());
  }
  reportTriangles(state, m, out.triangleCount());
  state.counters["cell_width"] = pr.params.cell_width;
}

void BM_FloatingLevel_Bunny(benchmark::State& state) { levelAtArg(state, bunny(), ClusterParams().method); }
SCENELOD_BENCHMARK(BM_FloatingLevel_Bunny)->Arg(50)->Arg(10)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_UniformLevel_Bunny(benchmark::State& state) { levelAtArg(state, bunny(), LodMethod::kUniform); }
SCENELOD_BENCHMARK(BM_UniformLevel_Bunny)->Arg(50)->Arg(10)->Unit(benchmark::kMillisecond);

// the once-per-mesh part: validation, grading, sort by weight
void BM_Prepare_Bunny(benchmark::State& state) {
  PreparedMesh p;
  for (auto _ : state) {
    prepareMesh(bunny(), ClusterParams(), p);
    benchmark::DoNotOptimize(p.order.data());
  }
  reportTriangles(state, bunny(), 0);
}
SCENELOD_BENCHMARK(BM_Prepare_Bunny)->Unit(benchmark::kMillisecond);

// meshopt_simplifySloppy to the triangle count our level at the same Arg produced
void BM_Sloppy_Bunny(benchmark::State& state) {
  const Mesh& m = bunny();
  const size_t target = prepared(m, double(state.range(0)) / 100.0).triangles;
  std::vector<unsigned int> dst(m.triangles.size());
  size_t n = 0;
  for (auto _ : state) {
    n = meshopt_simplifySloppy(dst.data(), m.triangles.data(), m.triangles.size(), &m.positions[0].x,
                               m.positions.size(), sizeof(glm::vec3), target * 3, 1.0f, nullptr);
    benchmark::DoNotOptimize(dst.data());
  }
  reportTriangles(state, m, n / 3);
}
SCENELOD_BENCHMARK(BM_Sloppy_Bunny)->Arg(50)->Arg(10)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_MeshoptSimplify_Bunny(benchmark::State& state) {
  const Mesh& m = bunny();
  const size_t target = prepared(m, double(state.range(0)) / 100.0).triangles;
  std::vector<unsigned int> dst(m.triangles.size());
  size_t n = 0;
  for (auto _ : state) {
    n = meshopt_simplify(dst.data(), m.triangles.data(), m.triangles.size(), &m.positions[0].x, m.positions.size(),
                         sizeof(glm::vec3), target * 3, 1.0f, 0, nullptr);
    benchmark::DoNotOptimize(dst.data());
  }
  reportTriangles(state, m, n / 3);
}
SCENELOD_BENCHMARK(BM_MeshoptSimplify_Bunny)->Arg(10)->Unit(benchmark::kMillisecond);

// a whole 8-level chain of the bunny: grading, sort, the w1 search unless w1 is given (the width
// keeping half the triangles), the levels in parallel on all threads, or on one
void chainOfBunny(benchmark::State& state, LodMethod method, bool w1_given, const char* label) {
  ChainParams cp;
  cp.level_count = 8;
  cp.cluster.method = method;
  if (w1_given) {
    ClusterParams params;
    params.method = method;
    cp.first_cell_width = prepared(bunny(), 0.5, params).params.cell_width;
  }
  LodChain chain;
  for (auto _ : state) {
    buildChain(bunny(), cp, chain);
    benchmark::DoNotOptimize(chain.levels.data());
  }
  reportTriangles(state, bunny(), chain.levels.back().mesh.triangleCount());
  state.SetLabel(label);
}

void BM_Chain8_Bunny(benchmark::State& state) {
  const bool given = state.range(0) == 1;
  chainOfBunny(state, ClusterParams().method, given, given ? "w1 given" : "w1 searched");
}
SCENELOD_BENCHMARK(BM_Chain8_Bunny)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_Chain8_Bunny_OneThread(benchmark::State& state) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
  chainOfBunny(state, ClusterParams().method, true, "w1 given, 1 thread");
}
SCENELOD_BENCHMARK(BM_Chain8_Bunny_OneThread)->Unit(benchmark::kMillisecond);

// the same chain on Rossignac & Borrel's uniform grid: the chain's floor without the floating
// cells' weight-ordered search (the grading and sort still run: prepareMesh does them for every method)
void BM_Chain8_Bunny_Uniform(benchmark::State& state) {
  const bool given = state.range(0) == 1;
  chainOfBunny(state, LodMethod::kUniform, given, given ? "uniform, w1 given" : "uniform, w1 searched");
}
SCENELOD_BENCHMARK(BM_Chain8_Bunny_Uniform)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_Sloppy10pct_Bunny(benchmark::State& state) {
  const Mesh& m = bunny();
  std::vector<unsigned int> dst(m.triangles.size());
  size_t n = 0;
  const size_t target = m.triangles.size() / 10 / 3 * 3;
  for (auto _ : state) {
    n = meshopt_simplifySloppy(dst.data(), m.triangles.data(), m.triangles.size(), &m.positions[0].x,
                               m.positions.size(), sizeof(glm::vec3), target, 1.0f, nullptr);
    benchmark::DoNotOptimize(dst.data());
  }
  reportTriangles(state, m, n / 3);
}
SCENELOD_BENCHMARK(BM_Sloppy10pct_Bunny)->Unit(benchmark::kMillisecond);

// one level on a generated mesh of about 1 M triangles, one thread: at 50 % and 25 % (a chain's first
// levels, whose cells are past every cache) as well as 10 % and 1 %
void BM_FloatingLevel_1M(benchmark::State& state) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
  levelAtArg(state, bigMesh(), ClusterParams().method);
}
SCENELOD_BENCHMARK(BM_FloatingLevel_1M)->Arg(50)->Arg(25)->Arg(10)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(5);

// Rossignac & Borrel's uniform grid at the same counts, one thread: the pipeline's floor without the
// floating cells' weight-ordered search (the same elimination, synthesis and output passes follow)
void BM_UniformLevel_1M(benchmark::State& state) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
  levelAtArg(state, bigMesh(), LodMethod::kUniform);
}
SCENELOD_BENCHMARK(BM_UniformLevel_1M)->Arg(50)->Arg(25)->Arg(10)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(5);

void BM_Sloppy_1M(benchmark::State& state) {
  const Mesh& m = bigMesh();
  const size_t target = prepared(m, double(state.range(0)) / 100.0).triangles;
  std::vector<unsigned int> dst(m.triangles.size());
  size_t n = 0;
  for (auto _ : state) {
    n = meshopt_simplifySloppy(dst.data(), m.triangles.data(), m.triangles.size(), &m.positions[0].x,
                               m.positions.size(), sizeof(glm::vec3), target * 3, 1.0f, nullptr);
    benchmark::DoNotOptimize(dst.data());
  }
  reportTriangles(state, m, n / 3);
}
SCENELOD_BENCHMARK(BM_Sloppy_1M)->Arg(50)->Arg(25)->Arg(10)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(5);

// peak extra memory (operator new) while building an 8-level chain, per input vertex and triangle;
// "retained" is what the finished chain holds, "transient" the rest of the peak. With `hand_over`
// the engine's own copy of the mesh (made before the baseline, like the input it already holds) is
// moved into the chain, buildChain(Mesh&&), so level 0 costs nothing extra. `morphs` as
// ChainParams::morphs (the geomorph targets are part of "retained").
void chainMemory(benchmark::State& state, const Mesh& m, bool hand_over, bool morphs = true) {
  long long peak_extra = 0, retained = 0;
  for (auto _ : state) {
    LodChain chain;
    ChainParams cp;
    cp.level_count = 8;
    cp.morphs = morphs;
    Mesh own = hand_over ? m : Mesh();
    const long long base = g_current.load();
    g_peak.store(base);
    if (hand_over) buildChain(std::move(own), cp, chain);
    else buildChain(m, cp, chain);
    peak_extra = g_peak.load() - base;
    retained = g_current.load() - base;
    benchmark::DoNotOptimize(chain.levels.data());
  }
  const double v = double(m.vertexCount()), t = double(m.triangleCount());
  const double budget = 64.0 * v + 16.0 * t;
  state.counters["peak_MB"] = double(peak_extra) / 1e6;
  state.counters["retained_MB"] = double(retained) / 1e6;
  state.counters["peak_over_budget"] = double(peak_extra) / budget;
  state.counters["transient_over_budget"] = double(peak_extra - retained) / budget;
  state.counters["budget_MB"] = budget / 1e6;
  state.SetLabel(std::string(hand_over ? "mesh handed over" : "mesh copied") + (morphs ? "" : ", no geomorphs"));
}
// Args: hand over (1) or copy (0) the mesh; geomorphs (1, the default) or none (0)
void BM_ChainMemory_Bunny(benchmark::State& state) {
  chainMemory(state, bunny(), state.range(0) == 1, state.range(1) == 1);
}
SCENELOD_BENCHMARK(BM_ChainMemory_Bunny)->ArgsProduct({{0, 1}, {1, 0}})->Unit(benchmark::kMillisecond)->Iterations(1);
void BM_ChainMemory_1M(benchmark::State& state) {
  chainMemory(state, bigMesh(), state.range(0) == 1, state.range(1) == 1);
}
SCENELOD_BENCHMARK(BM_ChainMemory_1M)->ArgsProduct({{0, 1}, {1, 0}})->Unit(benchmark::kMillisecond)->Iterations(1);
// 10 M triangles, the mesh copied: Arg 0 one sphere, 1 the scattered parts (a few seconds each);
// geomorphs (1) or none (0)
void BM_ChainMemory_10M(benchmark::State& state) {
  const Mesh& m = state.range(0) == 0 ? hugeSphere() : hugeScattered();
  chainMemory(state, m, false, state.range(1) == 1);
  state.counters["triangles"] = double(m.triangleCount());
  state.SetLabel(state.range(0) == 0 ? "one sphere" : "8,000 scattered spheres");
}
SCENELOD_BENCHMARK(BM_ChainMemory_10M)->ArgsProduct({{0, 1}, {1, 0}})->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
