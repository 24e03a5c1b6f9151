// MSFT_lod output (exportGlb with chains) re-imports to the same chains (importGltfLods).
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/demo_scene.h"
#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/lod_build.h"
#include "test_support.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

// a demo-scene subset with hand-made coarser levels: a decimated copy (every other triangle), and a
// thick-edge-and-point level
void makeChains(const SceneData& s, std::vector<LodChain>& chains) {
  chains.assign(s.meshes.size(), LodChain{});
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    LodLevel l0;
    l0.mesh = s.meshes[m].mesh;
    chains[m].levels.push_back(l0);
    LodLevel l1;
    l1.mesh = s.meshes[m].mesh;
    l1.mesh.triangles.clear();
    for (size_t t = 0; t < s.meshes[m].mesh.triangleCount(); t += 2)
      l1.mesh.triangles.insert(l1.mesh.triangles.end(), s.meshes[m].mesh.triangles.begin() + 3 * t,
                               s.meshes[m].mesh.triangles.begin() + 3 * t + 3);
    l1.cell_width = 0.05f;
    l1.max_error = 0.02f;
    l1.method = LodMethod::kFloatingNearest;
    chains[m].levels.push_back(l1);
    LodLevel l2;
    const Aabb b = computeBounds(s.meshes[m].mesh);
    l2.mesh.positions = {b.min, b.max, b.center()};
    l2.mesh.normals = {{0, 0, 1}, {0, 0, 1}, {0, 1, 0}};
    l2.mesh.colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    l2.mesh.edges = {0, 1};
    l2.mesh.edge_thickness = {0.125f};
    l2.mesh.points = {2};
    l2.cell_width = 0.4f;
    l2.max_error = 0.3f;
    l2.method = LodMethod::kFloatingNearest;
    chains[m].levels.push_back(l2);
    computeChainBounds(chains[m]);
  }
}

std::vector<glm::vec3> corners(const Mesh& m, const std::vector<uint32_t>& indices) {
  std::vector<glm::vec3> out;
  for (uint32_t i : indices) out.push_back(m.positions[i]);
  return out;
}

}  // namespace

TEST(LodGltf, MsftLodOutputReimportsToTheSameChains) {
  DemoSceneParams p;
  p.bunny_path = "";
  p.gearbox_count = 1;
  p.bunny_count = 1;
  p.segments = 12;
  SceneData s;
  ASSERT_TRUE(makeDemoScene(s, p).ok());
  s.meshes.pop_back();  // the 20k-triangle blob is not needed here: drop it and its node
  for (NodeData& n : s.nodes)
    if (n.mesh == static_cast<int32_t>(s.meshes.size())) n.mesh = -1;
  std::vector<LodChain> chains;
  makeChains(s, chains);
  std::vector<const LodChain*> ptrs;
  for (const LodChain& c : chains) ptrs.push_back(&c);
  const std::string path = scenelod::test::scratchDir() + "/lods.glb";
  const Error we = exportGlb(path, s, &ptrs);
  ASSERT_TRUE(we.ok()) << we.message;
  SceneData back;
  std::vector<LodChain> back_chains;
  const Error re = importGltfLods(path, back, back_chains);
  ASSERT_TRUE(re.ok()) << re.message;
  ASSERT_EQ(back.nodes.size(), s.nodes.size());
  ASSERT_EQ(back.meshes.size(), s.meshes.size());
  ASSERT_EQ(objectNodes(back), objectNodes(s));
  ASSERT_EQ(back_chains.size(), chains.size());
  for (size_t m = 0; m < chains.size(); ++m) {
    ASSERT_EQ(back_chains[m].levels.size(), chains[m].levels.size()) << "mesh " << m;
    for (size_t l = 0; l < chains[m].levels.size(); ++l) {
      const LodLevel &a = chains[m].levels[l], &b = back_chains[m].levels[l];
      SCOPED_TRACE("mesh " + std::to_string(m) + " level " + std::to_string(l));
      EXPECT_EQ(b.cell_width, a.cell_width);
      EXPECT_EQ(b.max_error, a.max_error);
      EXPECT_EQ(b.method, a.method);
      EXPECT_EQ(b.mesh.positions, a.mesh.positions);
      EXPECT_EQ(b.mesh.triangles, a.mesh.triangles);
      EXPECT_EQ(b.mesh.edges, a.mesh.edges);
      EXPECT_EQ(b.mesh.edge_thickness, a.mesh.edge_thickness);
      EXPECT_EQ(b.mesh.points, a.mesh.points);
      ASSERT_EQ(b.mesh.normals.size(), a.mesh.normals.size());
      for (size_t v = 0; v < a.mesh.normals.size(); ++v) EXPECT_NEAR(glm::length(b.mesh.normals[v] - a.mesh.normals[v]), 0.0f, 1e-6f);
      // every vertex inside the recomputed level sphere
      for (const glm::vec3& q : b.mesh.positions) EXPECT_LE(glm::length(q - b.bounds.center), b.bounds.radius);
    }
  }
  std::remove(path.c_str());
}

TEST(LodGltf, BuiltChainsSurviveTheMsftLodRoundTrip) {
  DemoSceneParams p;
  p.bunny_count = 0;
  p.gearbox_count = 1;
  p.segments = 12;
  SceneData s;
  ASSERT_TRUE(makeDemoScene(s, p).ok());
  LodBuildParams params;
  params.chain.level_count = 5;
  SceneLods lods;
  ASSERT_TRUE(buildLods(s, params, lods).ok());
  size_t edges = 0, points = 0;
  for (const LodChain& c : lods.chains)
    for (const LodLevel& l : c.levels) {
      edges += l.mesh.edgeCount();
      points += l.mesh.pointCount();
    }
  EXPECT_GT(edges, 0u);  // the thin fins and rods collapse into thick edges
  std::vector<const LodChain*> ptrs;
  for (const LodChain& c : lods.chains) ptrs.push_back(&c);
  const std::string path = scenelod::test::scratchDir() + "/built_lods.glb";
  ASSERT_TRUE(exportGlb(path, s, &ptrs).ok());
  SceneData back;
  std::vector<LodChain> chains;
  const Error e = importGltfLods(path, back, chains);
  ASSERT_TRUE(e.ok()) << e.message;
  ASSERT_EQ(chains.size(), lods.chains.size());
  for (size_t m = 0; m < chains.size(); ++m) {
    ASSERT_EQ(chains[m].levelCount(), lods.chains[m].levelCount()) << s.meshes[m].name;
    for (size_t l = 0; l < chains[m].levelCount(); ++l) {
      const LodLevel &a = lods.chains[m].levels[l], &b = chains[m].levels[l];
      SCOPED_TRACE(s.meshes[m].name + " level " + std::to_string(l));
      // the same primitives at the same positions, corner by corner (the importer may merge
      // vertices that the clustering left as exact duplicates, so indices can differ)
      EXPECT_EQ(corners(b.mesh, b.mesh.triangles), corners(a.mesh, a.mesh.triangles));
      EXPECT_EQ(corners(b.mesh, b.mesh.edges), corners(a.mesh, a.mesh.edges));
      EXPECT_EQ(corners(b.mesh, b.mesh.points), corners(a.mesh, a.mesh.points));
      if (a.mesh.edgeCount() > 0) {
        EXPECT_EQ(b.mesh.edge_thickness, a.mesh.edge_thickness);
      }
      EXPECT_EQ(b.cell_width, a.cell_width);
      EXPECT_EQ(b.max_error, a.max_error);
      EXPECT_EQ(b.method, a.method);
    }
  }
  std::remove(path.c_str());
}
