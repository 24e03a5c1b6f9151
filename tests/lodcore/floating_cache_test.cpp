// The floating-cell assignment's candidate cache (floating_cell_cluster.cpp, CandidateCache: the
// AVX2 flat grid of side w/2 with and without it) chooses the same cells as the SSE2 path.
#include <string>

#include <gtest/gtest.h>

#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/obj_io.h"
#include "test_hooks.h"
#include "test_support.h"

using namespace scenelod;

namespace {

struct Case {
  LodMethod method;
  CellShape shape;
};
// both joining rules with both cell shapes
constexpr Case kRules[] = {{LodMethod::kFloatingHeaviest, CellShape::kCube}, {LodMethod::kFloatingNearest, CellShape::kCube},
                           {LodMethod::kFloatingHeaviest, CellShape::kSphere}, {LodMethod::kFloatingNearest, CellShape::kSphere}};

// every rule and shape at widths where the cache is taken (at least 12 vertices per expected cell)
// and one where it is not: the cached run (its default, with cachedRun and without), the uncached
// AVX2 run and the SSE2 run give the same cells in the same order. Sphere cells make lists of more
// than 8 candidates (entries of several blocks); the coarsest widths fill an entry past its spare
// lanes.
void expectSameCells(const Mesh& m, std::initializer_list<float> widths) {
  PreparedMesh p;
  ClusterParams params;
  ASSERT_TRUE(prepareMesh(m, params, p).ok());
  for (Case c : kRules) {
    for (float w : widths) {
      SCOPED_TRACE(std::string(lodMethodName(c.method)) + " " + cellShapeName(c.shape) + " w=" + std::to_string(w));
      params.method = c.method;
      params.cell_shape = c.shape;
      params.cell_width = w;
      ClusterAssignment plain, uncached, cached;
      ClusterAssignment forced[2];  // no runs, runs
      {
        detail::HookGuard avx2(detail::setFloatingAvx2ForTest, false);
        ASSERT_TRUE(assignClusters(p, params, plain).ok());
        avx2.set(true);
        detail::HookGuard cache(detail::setFloatingCacheForTest, false);
        ASSERT_TRUE(assignClusters(p, params, uncached).ok());
        cache.set(true);
        ASSERT_TRUE(assignClusters(p, params, cached).ok());
        detail::HookGuard runs(detail::setFloatingCacheRunsForTest, 0);
        ASSERT_TRUE(assignClusters(p, params, forced[0]).ok());
        runs.set(1);
        ASSERT_TRUE(assignClusters(p, params, forced[1]).ok());
      }
      EXPECT_GT(plain.heaviest.size(), 1u);
      EXPECT_EQ(uncached.heaviest, plain.heaviest);
      EXPECT_EQ(uncached.cluster_of, plain.cluster_of);
      EXPECT_EQ(cached.heaviest, plain.heaviest);
      EXPECT_EQ(cached.cluster_of, plain.cluster_of);
      for (int runs = 0; runs < 2; ++runs) {
        SCOPED_TRACE(runs ? "runs" : "no runs");
        EXPECT_EQ(forced[runs].heaviest, plain.heaviest);
        EXPECT_EQ(forced[runs].cluster_of, plain.cluster_of);
      }
    }
  }
}

}  // namespace

TEST(FloatingCell, CandidateCacheChoosesTheSameCellsOnTheBunny) {
  SCENELOD_REQUIRE_BUNNY();
  Mesh bunny;
  ASSERT_TRUE(readObj(test::bunnyPath(), bunny).ok());
  // the bunny's 10 % (not cached), 5 %, 3 %, 2 % levels, and coarser: its chain's levels 3 to 8
  // (w1 = 0.0267405026 times 4 to 128)
  expectSameCells(bunny, {0.0721607581f, 0.104215436f, 0.135870472f, 0.172672614f, 0.3f, 0.6f, 0.10696201f, 0.213924021f,
                          0.427848041f, 0.855696082f, 1.71139216f, 3.42278433f});
}

TEST(FloatingCell, CandidateCacheChoosesTheSameCellsOnGeneratedMeshes) {
  // 40 k vertices on the sphere of radius ~1; the CAD part puts vertices exactly on cube faces
  expectSameCells(test::makeBumpySphere(200, 200), {0.05f, 0.1f, 0.2f, 0.45f, 0.9f});
  expectSameCells(test::makeCadPart(), {0.1f, 0.25f, 0.5f});
}
