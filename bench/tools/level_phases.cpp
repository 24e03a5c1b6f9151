// Where one clustering level spends its time: the phases of clusterPrepared timed apart (the
// assignment, the renumbering of large levels, elimination, synthesis, the output pass), one thread,
// minima over repetitions, for each level of a mesh's 8-level chain (its own widths, w_1 searched as
// buildChain does, and as there without the sorted copy of a small mesh's positions) or at the
// widths that keep given fractions of the triangles (as clusterPrepared, with the copy). The phases
// run in the level's order on the level's data, so their sum is the level's time less its
// statistics (the maximum displacement) and its allocations. Built and run by scripts/level-phases against a
// build's libscenelod_core.a. Not a unit test: it times.
// With `hash` last, the levels that would search the bricked grid of side w search the hash
// instead (the grid before the bricked one, for comparisons); the grid column names the one searched.
// With `uniform` last, the levels are Rossignac & Borrel's uniform grid instead of floating cells:
// the same elimination, synthesis and output passes after an assignment with no weight order, so
// the floor under any floating-cell assignment at that count (the grid column reads "-").
// Usage: level_phases bunny|sphere1M|MESH.obj chain|FRACTION[,FRACTION...] REPETITIONS [hash|uniform]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "cluster_internal.h"
#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/obj_io.h"
#include "test_hooks.h"

using namespace scenelod;
using Clock = std::chrono::steady_clock;

namespace scenelod::detail {
// floating_cell_cluster.cpp's switches (test_hooks.h), declared again weak so that the
// tool still links against the libraries of builds older than them (scripts/level-phases OTHER_BUILD)
__attribute__((weak)) int setFloatingBlockBricksForTest(int mode);
__attribute__((weak)) int lastFloatingGridForTest();
}  // namespace scenelod::detail

namespace {

int usage(const char* why) {
  std::fprintf(stderr,
               "level_phases: %s\nusage: level_phases bunny|sphere1M|MESH.obj chain|FRACTION[,FRACTION...] "
               "REPETITIONS [hash|uniform]\n",
               why);
  return 2;
}

double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

struct Row {
  std::string label;
  float width = 0.0f;
  uint32_t clusters = 0;
  size_t triangles = 0;
  int grid = -1;  // lastFloatingGridForTest: 0 flat, 1 bricked, 2 hash, 3 hash (too many bricks)
  // minima, ms: assign, renumber, elimination, synthesis, output
  double phase[5];
  Row() { std::fill(std::begin(phase), std::end(phase), std::numeric_limits<double>::infinity()); }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4 && argc != 5) return usage("three or four arguments expected");
  const char* option = argc == 5 ? argv[4] : "";
  const bool uniform = std::strcmp(option, "uniform") == 0;
  if (std::strcmp(option, "hash") == 0) {
    if (!detail::setFloatingBlockBricksForTest) return usage("this build's library has no bricked grid to switch off");
    detail::setFloatingBlockBricksForTest(0);
  } else if (*option != '\0' && !uniform) {
    return usage("the fourth argument, if any, must be `hash` or `uniform`");
  }
  const int repetitions = std::atoi(argv[3]);
  if (repetitions < 1) return usage("REPETITIONS must be at least 1");
  Mesh m;
  if (std::strcmp(argv[1], "bunny") == 0) {
    if (Error e = readObj(SCENELOD_BUNNY_PATH, m); !e.ok()) return usage(e.message.c_str());
  } else if (std::strcmp(argv[1], "sphere1M") == 0) {
    m = test::makeBumpySphere(720, 720);
  } else if (Error e = readObj(argv[1], m); !e.ok()) {
    return usage(e.message.c_str());
  }
  if (m.triangleCount() == 0) return usage("the mesh has no triangles");

  // one thread, as a level of a chain runs (the levels, not the phases, go in parallel), and the
  // prepare on one thread too
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const bool chain_levels = std::strcmp(argv[2], "chain") == 0;
  ClusterParams params;
  if (uniform) params.method = LodMethod::kUniform;
  PreparedMesh p;
  double prepare_ms = std::numeric_limits<double>::infinity();
  for (int i = 0; i < repetitions; ++i) {
    const Clock::time_point t0 = Clock::now();
    if (Error e = prepareMesh(m, params, p); !e.ok()) return usage(e.message.c_str());
    prepare_ms = std::min(prepare_ms, msSince(t0));
  }
  std::vector<Row> rows;
  if (chain_levels) {
    // the chain's own widths (buildChain searches w_1 for half the triangles)
    ChainParams cp;
    cp.cluster = params;
    LodChain chain;
    if (Error e = buildChain(m, cp, chain); !e.ok()) return usage(e.message.c_str());
    for (size_t k = 1; k < chain.levels.size(); ++k) {
      Row r;
      r.label = "level " + std::to_string(k);
      r.width = chain.levels[k].cell_width;
      rows.push_back(r);
    }
    // a chain's levels of a small mesh read its positions through the order, the sorted copy
    // dropped (as buildChain does); single levels (clusterPrepared) keep it
    if (p.sorted_positions.size() * sizeof(glm::vec3) < detail::kSortedCopyMinBytes)
      std::vector<glm::vec3>().swap(p.sorted_positions);
  } else {
    std::stringstream list(argv[2]);
    std::string item;
    while (std::getline(list, item, ',')) {
      const double fraction = std::atof(item.c_str());
      if (!(fraction > 0.0 && fraction < 1.0)) return usage("each FRACTION must be in (0, 1)");
      Row r;
      r.label = item;
      const size_t target = std::max<size_t>(1, size_t(double(m.triangleCount()) * fraction));
      if (Error e = findCellWidthForTarget(p, params, target, r.width, 0.01); !e.ok()) return usage(e.message.c_str());
      rows.push_back(r);
    }
  }
  for (Row& r : rows) {
    ClusterParams cp = params;
    cp.cell_width = r.width;
    for (int i = 0; i < repetitions; ++i) {
      detail::Assignment a;
      detail::Eliminated el;
      detail::Representatives rep;
      Mesh out;
      double t[5];
      Clock::time_point t0 = Clock::now();
      if (Error e = detail::assign(p, cp, a); !e.ok()) return usage(e.message.c_str());
      t[0] = msSince(t0);
      t0 = Clock::now();
      detail::renumberByFirstVertex(a);  // as clusterLevelParts: only levels of many clusters
      t[1] = msSince(t0);
      t0 = Clock::now();
      detail::eliminate(p, a, cp.keep_edges, cp.keep_points, true, el);
      t[2] = msSince(t0);
      t0 = Clock::now();
      detail::synthesize(p, a, cp.synthesis, rep);
      t[3] = msSince(t0);
      t0 = Clock::now();
      detail::buildOutputMesh(el, rep, cp.crease_angle_deg, out);
      t[4] = msSince(t0);
      for (int k = 0; k < 5; ++k) r.phase[k] = std::min(r.phase[k], t[k]);
      r.clusters = a.cluster_count;
      r.triangles = out.triangleCount();
      if (detail::lastFloatingGridForTest && !uniform) r.grid = detail::lastFloatingGridForTest();
    }
  }

  std::printf("%s: %zu vertices, %zu triangles; %s; prepare %.3f ms; all on one thread, minima of %d (ms)\n\n",
              argv[1], m.vertexCount(), m.triangleCount(), uniform ? "uniform grid" : "floating cells", prepare_ms,
              repetitions);
  std::printf(
      "| level | cell width | clusters | triangles | grid | assign | renumber | elimination | synthesis | output | sum |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  static const char* const kGridNames[] = {"flat", "bricked", "hash", "hash (too many bricks)"};
  double total[6] = {0, 0, 0, 0, 0, 0};
  for (const Row& r : rows) {
    double sum = 0.0;
    for (int k = 0; k < 5; ++k) sum += r.phase[k], total[k] += r.phase[k];
    total[5] += sum;
    std::printf("| %s | %.6g | %u | %zu | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", r.label.c_str(), r.width,
                r.clusters, r.triangles, r.grid >= 0 && r.grid <= 3 ? kGridNames[r.grid] : "-", r.phase[0],
                r.phase[1], r.phase[2], r.phase[3], r.phase[4], sum);
  }
  if (rows.size() > 1)
    std::printf("| all | | | | | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", total[0], total[1], total[2], total[3],
                total[4], total[5]);
  return 0;
}
