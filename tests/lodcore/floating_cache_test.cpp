// The floating-cell assignment's AVX2 fast paths (floating_cell_cluster.cpp): the candidate cache
// (CandidateCache: the AVX2 flat grid of side w/2 with and without it, and the SSE2 path) and the
// bricked heads' 2 x 2 x 2 gather (BrickHeads::gather8) choose the same cells as the SSE2 path.
#include <string>

#include <gtest/gtest.h>

#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/obj_io.h"
#include "test_support.h"

using namespace scenelod;

namespace scenelod::detail {
// floating_cell_cluster.cpp's hidden switches (see floating_cell_test.cpp)
void setFloatingPathsForTest(bool avx2, bool short_heads, bool bricks);
void setFloatingCacheForTest(bool cache);
void setFloatingCacheRunsForTest(int runs);
void setFloatingCacheFlatForTest(int flat);
}  // namespace scenelod::detail

namespace {

struct Case {
  LodMethod method;
  CellShape shape;
};
// both joining rules with both cell shapes
constexpr Case kRules[] = {{LodMethod::kFloatingHeaviest, CellShape::kCube}, {LodMethod::kFloatingNearest, CellShape::kCube},
                           {LodMethod::kFloatingHeaviest, CellShape::kSphere}, {LodMethod::kFloatingNearest, CellShape::kSphere}};

// every rule and shape at widths where the cache is taken (at least 12 vertices per expected cell)
// and one where it is not, with short and 32-bit heads: the cached run (its default, and cachedRun
// with the entries' centres, on entries of indices and not at all, each at every cached width and
// each on the cache's bricked and flat slots), the uncached AVX2 run and the SSE2 run give the same
// cells in the same order. Sphere cells make lists of more than 8
// candidates (entries of several blocks); the coarsest widths fill an entry past its spare lanes.
void expectSameCells(const Mesh& m, std::initializer_list<float> widths) {
  PreparedMesh p;
  ClusterParams params;
  ASSERT_TRUE(prepareMesh(m, params, p).ok());
  for (Case c : kRules) {
    for (float w : widths) {
      for (bool short_heads : {true, false}) {
        SCOPED_TRACE(std::string(lodMethodName(c.method)) + " " + cellShapeName(c.shape) + " w=" + std::to_string(w) +
                     (short_heads ? " short heads" : " 32-bit heads"));
        params.method = c.method;
        params.cell_shape = c.shape;
        params.cell_width = w;
        ClusterAssignment plain, uncached, cached;
        detail::setFloatingPathsForTest(false, short_heads, false);
        const bool plain_ok = assignClusters(p, params, plain).ok();
        detail::setFloatingPathsForTest(true, short_heads, false);
        detail::setFloatingCacheForTest(false);
        const bool uncached_ok = assignClusters(p, params, uncached).ok();
        detail::setFloatingCacheForTest(true);
        const bool cached_ok = assignClusters(p, params, cached).ok();
        // runs with centres, on indices, none; bricked then flat slots
        ClusterAssignment forced[2][3];
        bool forced_ok = true;
        for (int flat = 0; flat < 2; ++flat) {
          detail::setFloatingCacheFlatForTest(flat);
          for (int runs = 0; runs < 3; ++runs) {
            detail::setFloatingCacheRunsForTest(runs == 2 ? 0 : runs + 1);
            forced_ok = assignClusters(p, params, forced[flat][runs]).ok() && forced_ok;
          }
        }
        detail::setFloatingCacheFlatForTest(-1);
        detail::setFloatingCacheRunsForTest(-1);
        detail::setFloatingPathsForTest(true, true, true);
        ASSERT_TRUE(plain_ok && uncached_ok && cached_ok && forced_ok);
        EXPECT_GT(plain.heaviest.size(), 1u);
        EXPECT_EQ(uncached.heaviest, plain.heaviest);
        EXPECT_EQ(uncached.cluster_of, plain.cluster_of);
        EXPECT_EQ(cached.heaviest, plain.heaviest);
        EXPECT_EQ(cached.cluster_of, plain.cluster_of);
        for (int flat = 0; flat < 2; ++flat)
          for (int runs = 0; runs < 3; ++runs) {
            SCOPED_TRACE(std::string(flat ? "flat" : "bricked") + " slots, runs " +
                         (runs == 0 ? "with centres" : runs == 1 ? "on indices" : "none"));
            EXPECT_EQ(forced[flat][runs].heaviest, plain.heaviest);
            EXPECT_EQ(forced[flat][runs].cluster_of, plain.cluster_of);
          }
      }
    }
  }
}

// every rule and shape: the AVX2 run on short heads in bricks where they are taken (fine widths:
// cubes of side w, a flat array of short heads over 16 bytes per vertex), the SSE2 run on the same
// bricks and the SSE2 run on flat 32-bit heads give the same cells in the same order
void expectSameCellsInBricks(const Mesh& m, std::initializer_list<float> widths) {
  PreparedMesh p;
  ClusterParams params;
  ASSERT_TRUE(prepareMesh(m, params, p).ok());
  for (Case c : kRules) {
    for (float w : widths) {
      SCOPED_TRACE(std::string(lodMethodName(c.method)) + " " + cellShapeName(c.shape) + " w=" + std::to_string(w));
      params.method = c.method;
      params.cell_shape = c.shape;
      params.cell_width = w;
      ClusterAssignment plain, sse_bricks, avx_bricks;
      detail::setFloatingPathsForTest(false, false, false);
      const bool plain_ok = assignClusters(p, params, plain).ok();
      detail::setFloatingPathsForTest(false, true, true);
      const bool sse_ok = assignClusters(p, params, sse_bricks).ok();
      detail::setFloatingPathsForTest(true, true, true);
      const bool avx_ok = assignClusters(p, params, avx_bricks).ok();
      ASSERT_TRUE(plain_ok && sse_ok && avx_ok);
      EXPECT_GT(plain.heaviest.size(), 1u);
      EXPECT_EQ(sse_bricks.heaviest, plain.heaviest);
      EXPECT_EQ(sse_bricks.cluster_of, plain.cluster_of);
      EXPECT_EQ(avx_bricks.heaviest, plain.heaviest);
      EXPECT_EQ(avx_bricks.cluster_of, plain.cluster_of);
    }
  }
}

}  // namespace

TEST(FloatingCell, BrickedHeadsChooseTheSameCellsOnTheBunny) {
  SCENELOD_REQUIRE_BUNNY();
  Mesh bunny;
  ASSERT_TRUE(readObj(test::bunnyPath(), bunny).ok());
  // the bunny's 50 % level and finer and coarser widths around it
  expectSameCellsInBricks(bunny, {0.0267405026f, 0.015f, 0.02f, 0.035f});
}

TEST(FloatingCell, BrickedHeadsChooseTheSameCellsOnGeneratedMeshes) {
  // 40 k vertices on the sphere of radius ~1; the CAD part puts vertices exactly on cube faces
  expectSameCellsInBricks(test::makeBumpySphere(200, 200), {0.025f, 0.03f, 0.035f});
  expectSameCellsInBricks(test::makeCadPart(), {0.01f, 0.02f, 0.03f});
}

// the bricked grid of side w/2 (3 x 3 x 3 cubes: BrickHeads::rows27 on SSE2, plan27/heads27 on
// AVX2), taken where its flat short heads would pass 16 bytes per vertex but fit the dense budget:
// the bunny's chain level 2 (w = 0.0535) and around it, the sphere at 0.055-0.065, the CAD part
// (vertices on cube faces, 1 k vertices: bricks allocated between a vertex's plan and its gather)
TEST(FloatingCell, BrickedHalfWidthCubesChooseTheSameCellsOnGeneratedMeshes) {
  expectSameCellsInBricks(test::makeBumpySphere(200, 200), {0.055f, 0.06f, 0.065f});
  expectSameCellsInBricks(test::makeCadPart(), {0.1f, 0.12f, 0.14f});
}

TEST(FloatingCell, BrickedHalfWidthCubesChooseTheSameCellsOnTheBunny) {
  SCENELOD_REQUIRE_BUNNY();
  Mesh bunny;
  ASSERT_TRUE(readObj(test::bunnyPath(), bunny).ok());
  expectSameCellsInBricks(bunny, {0.05f, 0.0534810051f, 0.06f});
}

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
