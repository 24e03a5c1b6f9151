// buildOutputMesh (lodcore/src/normals.cpp): its shortcuts against the reference output pass.
#include <cmath>
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

// The output pass's smooth test over the faces, its corner lists for the clusters that fail it,
// its four-face lanes and its eight-corner path give the bits of the reference (every corner's sum
// by the scalar loop, one cluster at a time): every output array, at crease angles from 0 to 180
// degrees, fine and coarse cells, both variants, on smooth, bumpy, sharp (the CAD part, with
// colours), flat and scanned (the bunny, where installed) meshes.
TEST(OutputPass, ShortcutsGiveTheReferenceBits) {
  std::vector<std::pair<std::string, Mesh>> meshes;
  meshes.emplace_back("bumpy", test::makeBumpySphere(90, 120));
  meshes.emplace_back("sphere", test::makeSphere(glm::vec3(0.3f, -0.2f, 0.1f), 0.8f, 40, 50));
  meshes.emplace_back("grid", test::makeGrid(40, 1.0f));
  meshes.emplace_back("box", test::makeBox(glm::vec3(-0.4f), glm::vec3(0.5f), 12));
  {
    Mesh cad = test::makeCadPart();
    cad.colors.resize(cad.positions.size());
    for (size_t i = 0; i < cad.colors.size(); ++i)
      cad.colors[i] = glm::vec3(float(i % 7) / 7.0f, float(i % 5) / 5.0f, float(i % 3) / 3.0f);
    meshes.emplace_back("cad", std::move(cad));
  }
  {
    Mesh bunny;
    if (test::fileExists(test::bunnyPath()) && readObj(test::bunnyPath(), bunny).ok())
      meshes.emplace_back("bunny", std::move(bunny));
  }
  detail::HookGuard avx2_paths(detail::useAvx2Paths, true);
  detail::HookGuard reference(detail::useOutputReference, false);
  size_t levels = 0, split = 0;
  for (const auto& [name, m] : meshes)
    for (bool avx2 : {false, true})
      for (float w : {0.01f, 0.027f, 0.07f, 0.17f})
        for (float angle : {0.0f, 20.0f, 60.0f, 90.0f, 180.0f}) {
          ClusterParams p;
          p.cell_width = w;
          p.crease_angle_deg = angle;
          avx2_paths.set(avx2);
          Mesh fast, ref;
          reference.set(false);
          ASSERT_TRUE(clusterMesh(m, p, fast).ok());
          reference.set(true);
          ASSERT_TRUE(clusterMesh(m, p, ref).ok());
          SCOPED_TRACE(name + (avx2 ? " avx2" : " sse2") + " w=" + std::to_string(w) + " crease " + std::to_string(angle));
          EXPECT_TRUE(sameBits(fast.positions, ref.positions));
          EXPECT_TRUE(sameBits(fast.normals, ref.normals));
          EXPECT_TRUE(sameBits(fast.colors, ref.colors));
          EXPECT_TRUE(sameBits(fast.triangles, ref.triangles));
          EXPECT_TRUE(sameBits(fast.edges, ref.edges));
          EXPECT_TRUE(sameBits(fast.edge_thickness, ref.edge_thickness));
          EXPECT_TRUE(sameBits(fast.points, ref.points));
          levels += ref.triangleCount() > 0;
          split += ref.vertexCount() > ref.triangleCount() / 2 + 2;  // crease copies (closed meshes: V ~ T / 2)
        }
  EXPECT_GT(levels, 150u);
  EXPECT_GT(split, 20u);
}
