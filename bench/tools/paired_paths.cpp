// Paired A/B of the clustering's switchable code paths on this CPU: every pair runs one phase with a
// path on and then off (the order alternating from pair to pair), so the slow drifts of a shared
// machine fall on both sides alike; prints per path the minima and the median and quartiles of the
// per-pair ratios time off / time on (above 1: the path helps on this machine). The paths are the
// library's private test hooks, each of which gives the same bits on and off (tests compare them), so
// this only asks which is faster where; a path the level does not take (the candidate cache at
// fine levels, the bricked grid where flat heads fit) measures about 1. Built and run by
// scripts/paired-paths against a build's libscenelod_core.a. Not a unit test: it times.
// Usage: paired_paths bunny|sphere1M FRACTION PAIRS [NAME]   (FRACTION of the triangles kept, e.g.
// 0.5; NAME: only the paths whose name contains it)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "cluster_internal.h"
#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/obj_io.h"
#include "test_hooks.h"

namespace scenelod::detail {
// the floating cells' switches (test_hooks.h), declared again weak so that the tool still links
// against the libraries of builds older than them (their rows are then skipped)
__attribute__((weak)) bool setFloatingAvx2ForTest(bool on);
__attribute__((weak)) bool setFloatingCacheForTest(bool on);
__attribute__((weak)) int setFloatingCacheRunsForTest(int runs);
__attribute__((weak)) int setFloatingBlockBricksForTest(int mode);
}  // namespace scenelod::detail

using namespace scenelod;
using Clock = std::chrono::steady_clock;

namespace {

int usage(const char* why) {
  std::fprintf(stderr, "paired_paths: %s\nusage: paired_paths bunny|sphere1M FRACTION PAIRS [NAME]\n", why);
  return 2;
}

struct Path {
  const char* name;
  bool (*hook)(bool);
  std::function<void()> run;
  bool built = true;  // false: this build's library has no such switch
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4 && argc != 5) return usage("three or four arguments expected");
  Mesh m;
  if (std::strcmp(argv[1], "bunny") == 0) {
    if (Error e = readObj(SCENELOD_BUNNY_PATH, m); !e.ok()) return usage(e.message.c_str());
  } else if (std::strcmp(argv[1], "sphere1M") == 0) {
    m = test::makeBumpySphere(720, 720);
  } else {
    return usage("the mesh is bunny or sphere1M");
  }
  const double fraction = std::atof(argv[2]);
  const int pairs = std::atoi(argv[3]);
  if (!(fraction > 0.0 && fraction < 1.0)) return usage("FRACTION must be in (0, 1)");
  if (pairs < 4) return usage("PAIRS must be at least 4");

  ClusterParams params;
  PreparedMesh p;
  if (Error e = prepareMesh(m, params, p); !e.ok()) return usage(e.message.c_str());
  const size_t target = size_t(double(m.triangleCount()) * fraction);
  if (Error e = findCellWidthForTarget(p, params, target, params.cell_width, 0.01); !e.ok()) return usage(e.message.c_str());
  detail::Assignment a;
  if (Error e = detail::assign(p, params, a); !e.ok()) return usage(e.message.c_str());
  detail::Eliminated eliminated;
  detail::eliminate(p, a, params.keep_edges, params.keep_points, true, eliminated);
  detail::Representatives representatives;
  detail::synthesize(p, a, params.synthesis, representatives);

  auto elimination = [&] {
    detail::Eliminated e;
    detail::eliminate(p, a, params.keep_edges, params.keep_points, true, e);
  };
  auto synthesis = [&] {
    detail::Representatives r;
    detail::synthesize(p, a, params.synthesis, r);
  };
  auto output = [&] {
    detail::Eliminated e = eliminated;  // buildOutputMesh consumes its input
    Mesh out;
    detail::buildOutputMesh(e, representatives, params.crease_angle_deg, out);
  };
  auto level = [&] {
    Mesh out;
    clusterPrepared(p, params, out);
  };
  auto assignment = [&] {
    detail::Assignment as;
    detail::assignFloating(p, params.cell_width, params.cell_shape, params.method == LodMethod::kFloatingNearest, as);
  };
  auto prepare = [&] {
    PreparedMesh q;
    prepareMesh(m, params, q);
  };
  const std::vector<Path> paths = {
      {"AVX2 variants: elimination", detail::useAvx2Paths, elimination},
      {"AVX2 variants: synthesis", detail::useAvx2Paths, synthesis},
      {"AVX2 variants: output pass", detail::useAvx2Paths, output},
      {"AVX2 variants: prepare", detail::useAvx2Paths, prepare},
      {"AVX2 variants: whole level", detail::useAvx2Paths, level},
      {"repeated edge drop: elimination", detail::useRepeatedEdgeDrop, elimination},
      {"eigenvalue lanes: synthesis", detail::useEigenvalueLanes, synthesis},
      {"grouped synthesis: synthesis", detail::useGroupedSynthesis, synthesis},
      {"floating AVX2: assignment", [](bool on) { return detail::setFloatingAvx2ForTest(on); }, assignment,
       detail::setFloatingAvx2ForTest != nullptr},
      {"candidate cache: assignment", [](bool on) { return detail::setFloatingCacheForTest(on); }, assignment,
       detail::setFloatingCacheForTest != nullptr},
      {"cache runs: assignment", [](bool on) { return detail::setFloatingCacheRunsForTest(on ? -1 : 0) != 0; },
       assignment, detail::setFloatingCacheRunsForTest != nullptr},
      // on: the default (the bricked grid of side w where it fits), off: the hash
      {"bricked grid: assignment", [](bool on) { return detail::setFloatingBlockBricksForTest(on ? -1 : 0) != 0; },
       assignment, detail::setFloatingBlockBricksForTest != nullptr},
      // last: the hook(true) after each pair leaves it on always, not by size as by default
      {"renumbering: whole level", [](bool on) { return detail::setRenumberingForTest(on ? 1 : 0) != 0; }, level},
  };
  std::printf("%s, %zu of %zu triangles' width (%.9g), %d pairs; ratio = time off / time on\n", argv[1], target,
              m.triangleCount(), params.cell_width, pairs);
  for (const Path& path : paths) {
    if (!path.built || (argc == 5 && !std::strstr(path.name, argv[4]))) continue;
    std::vector<double> ratio, on_ms, off_ms;
    for (int i = 0; i < pairs; ++i) {
      double t[2] = {0.0, 0.0};  // on, off
      for (int k = 0; k < 2; ++k) {
        const bool on = ((i + k) & 1) == 0;
        path.hook(on);
        const Clock::time_point t0 = Clock::now();
        path.run();
        t[on ? 0 : 1] = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      }
      path.hook(true);
      on_ms.push_back(t[0]);
      off_ms.push_back(t[1]);
      ratio.push_back(t[1] / t[0]);
    }
    std::sort(ratio.begin(), ratio.end());
    std::printf("  %-32s on min %8.3f ms, off min %8.3f ms, ratio median %.3f (quartiles %.3f-%.3f)\n", path.name,
                *std::min_element(on_ms.begin(), on_ms.end()), *std::min_element(off_ms.begin(), off_ms.end()),
                ratio[ratio.size() / 2], ratio[ratio.size() / 4], ratio[3 * ratio.size() / 4]);
  }
  return 0;
}
