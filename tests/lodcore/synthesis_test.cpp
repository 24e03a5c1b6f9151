// synthesize's quadric solve: its eigenvalue lanes against the one-cluster form.
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/cluster.h"
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
