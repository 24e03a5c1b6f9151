// synthesize's quadric solve: its eigenvalue lanes against the one-cluster form; the grouped pass of
// fine levels against the single pass.
#include <cstring>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/obj_io.h"
#include "test_hooks.h"
#include "test_support.h"

using namespace scenelod;

namespace {

using test::sameBits;

}  // namespace

// Quadric synthesis solving rank-deficient clusters four at a time in lanes, and clamping floating
// cells' representatives in lanes, gives the bits of solving and clamping them one at a time (the
// lanes off; a clamp's bounds computed as -w/2 and w/2 instead of cellBox's (c -+ w/2) - c fail 12 checks): flat (the grid: rank 1), curved in one direction (the cylinder: rank 2), smooth and
// bumpy (spheres: mostly rank 1 and 2 at fine cells), sharp (the CAD part, the box: full rank and
// degenerate mixes) and scanned (the bunny, where it is installed), both cell shapes, coarse and
// fine levels, baseline and AVX2 variants.
TEST(Synthesis, EigenvalueLanesGiveTheOneClusterBits) {
  std::vector<std::pair<std::string, Mesh>> meshes;
  meshes.emplace_back("bumpy", test::makeBumpySphere(90, 120));
  meshes.emplace_back("sphere", test::makeSphere(glm::vec3(0.3f, -0.2f, 0.1f), 0.8f, 60, 80));
  meshes.emplace_back("grid", test::makeGrid(60, 1.0f));
  meshes.emplace_back("cylinder", test::makeCylinder(-0.5f, 0.5f, 0.3f, 40, 60));
  meshes.emplace_back("box", test::makeBox(glm::vec3(-0.4f), glm::vec3(0.5f), 12));
  meshes.emplace_back("cad", test::makeCadPart());
  {
    Mesh bunny;
    if (test::fileExists(test::bunnyPath()) && readObj(test::bunnyPath(), bunny).ok())
      meshes.emplace_back("bunny", std::move(bunny));
  }
  detail::HookGuard eigen_lanes(detail::useEigenvalueLanes, true);
  detail::HookGuard avx2_paths(detail::useAvx2Paths, true);
  size_t levels = 0;
  for (const auto& [name, m] : meshes)
    for (bool avx2 : {false, true})
      for (CellShape shape : {CellShape::kCube, CellShape::kSphere})
        for (float w : {0.008f, 0.02f, 0.05f, 0.15f}) {
          ClusterParams p;
          p.synthesis = Synthesis::kQuadric;
          p.cell_shape = shape;
          p.cell_width = w;
          avx2_paths.set(avx2);
          Mesh lanes, one;
          eigen_lanes.set(true);
          ASSERT_TRUE(clusterMesh(m, p, lanes).ok());
          eigen_lanes.set(false);
          ASSERT_TRUE(clusterMesh(m, p, one).ok());
          SCOPED_TRACE(name + (avx2 ? " avx2 " : " sse2 ") + cellShapeName(shape) + " w=" + std::to_string(w));
          EXPECT_TRUE(sameBits(lanes.positions, one.positions));
          EXPECT_TRUE(sameBits(lanes.normals, one.normals));
          EXPECT_TRUE(sameBits(lanes.triangles, one.triangles));
          levels += one.triangleCount() > 0;
        }
  EXPECT_GE(levels, 6u * 16u);
}

// The grouped pass of fine levels (clusters of one vertex summed and finished apart, the others four
// at a time from a list of their vertices) gives the single pass's bits: every synthesis, both cell
// shapes, floating and uniform cells, coloured (the CAD part) and plain meshes, baseline and AVX2
// variants, at widths where the grouped pass is taken (more than 16 bytes of single-pass sums, 92 a
// cluster, per vertex: from about one cluster per 5.75 vertices) and one where it is not.
TEST(Synthesis, GroupedPassGivesTheSinglePassBits) {
  std::vector<std::pair<std::string, Mesh>> meshes;
  meshes.emplace_back("bumpy", test::makeBumpySphere(90, 120));
  meshes.emplace_back("grid", test::makeGrid(60, 1.0f));
  meshes.emplace_back("cylinder", test::makeCylinder(-0.5f, 0.5f, 0.3f, 40, 60));
  meshes.emplace_back("cad", test::makeCadPart());
  {
    Mesh bunny;
    if (test::fileExists(test::bunnyPath()) && readObj(test::bunnyPath(), bunny).ok())
      meshes.emplace_back("bunny", std::move(bunny));
  }
  detail::HookGuard grouped(detail::useGroupedSynthesis, true);
  detail::HookGuard avx2_paths(detail::useAvx2Paths, true);
  size_t grouped_levels = 0;
  for (const auto& [name, m] : meshes)
    for (LodMethod method : {LodMethod::kFloatingNearest, LodMethod::kFloatingHeaviest, LodMethod::kUniform})
      for (Synthesis synthesis : {Synthesis::kQuadric, Synthesis::kMean, Synthesis::kHeaviest}) {
        ClusterParams p;
        p.method = method;
        p.synthesis = synthesis;
        PreparedMesh prepared;
        ASSERT_TRUE(prepareMesh(m, p, prepared).ok());
        const float extent = glm::length(prepared.bounds.max - prepared.bounds.min);
        for (bool avx2 : {false, true})
          for (CellShape shape : {CellShape::kCube, CellShape::kSphere})
            for (float f : {0.004f, 0.008f, 0.015f, 0.03f}) {
              p.cell_shape = shape;
              p.cell_width = f * extent;
              avx2_paths.set(avx2);
              Mesh grouped_mesh, single;
              ClusterStats stats;
              grouped.set(true);
              ASSERT_TRUE(clusterPrepared(prepared, p, grouped_mesh, &stats).ok());
              grouped.set(false);
              ASSERT_TRUE(clusterPrepared(prepared, p, single).ok());
              SCOPED_TRACE(name + (avx2 ? " avx2 " : " sse2 ") + lodMethodName(method) + " " +
                           synthesisName(synthesis) + " " + cellShapeName(shape) + " f=" + std::to_string(f));
              EXPECT_TRUE(sameBits(grouped_mesh.positions, single.positions));
              EXPECT_TRUE(sameBits(grouped_mesh.normals, single.normals));
              EXPECT_TRUE(sameBits(grouped_mesh.colors, single.colors));
              EXPECT_TRUE(sameBits(grouped_mesh.triangles, single.triangles));
              EXPECT_TRUE(sameBits(grouped_mesh.edges, single.edges));
              EXPECT_TRUE(sameBits(grouped_mesh.points, single.points));
              grouped_levels += stats.cluster_count * 92 > 16 * m.vertexCount();
            }
      }
  EXPECT_GE(grouped_levels, 4u * 3u * 3u * 2u * 2u);
}
