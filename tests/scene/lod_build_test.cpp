#include "scenelod/scene/lod_build.h"

#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "scenelod/scene/demo_scene.h"
#include "scenelod/scene/scene.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

SceneData smallDemo() {
  DemoSceneParams p;
  p.bunny_path = "";
  p.gearbox_count = 2;
  p.bunny_count = 2;
  p.segments = 16;
  SceneData s;
  EXPECT_TRUE(makeDemoScene(s, p).ok());
  return s;
}

LodBuildParams params() {
  LodBuildParams p;
  p.chain.level_count = 4;
  return p;
}

struct ProgressLog {
  std::vector<double> fractions;
};

}  // namespace

TEST(LodBuild, EveryMeshGetsAChainWhoseLevelsLieInsideTheirSpheres) {
  const SceneData s = smallDemo();
  Scene scene;
  ASSERT_TRUE(Scene::fromSceneData(s, scene).ok());
  SceneLods lods;
  LodBuildParams p = params();
  ProgressLog log;
  p.progress.fn = [](void* user, double f, const char*) { static_cast<ProgressLog*>(user)->fractions.push_back(f); };
  p.progress.user = &log;
  const Error e = buildLods(s, p, lods, &scene);
  ASSERT_TRUE(e.ok()) << e.message;
  ASSERT_EQ(lods.chains.size(), s.meshes.size());
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    const LodChain& c = lods.chains[m];
    ASSERT_GE(c.levelCount(), 2u) << s.meshes[m].name;
    EXPECT_EQ(c.levels[0].mesh.positions, s.meshes[m].mesh.positions);
    for (size_t l = 0; l < c.levelCount(); ++l) {
      const LodLevel& level = c.levels[l];
      for (const glm::vec3& q : level.mesh.positions) {
        ASSERT_LE(glm::length(q - level.bounds.center), level.bounds.radius) << s.meshes[m].name << " level " << l;
        ASSERT_LE(glm::length(q - lods.chain_spheres[m].center), lods.chain_spheres[m].radius) << s.meshes[m].name;
      }
    }
  }
  // progress: starts at 0, never decreases, ends at 1
  ASSERT_GE(log.fractions.size(), s.meshes.size());
  EXPECT_EQ(log.fractions.front(), 0.0);
  EXPECT_EQ(log.fractions.back(), 1.0);
  for (size_t i = 1; i < log.fractions.size(); ++i) EXPECT_GE(log.fractions[i], log.fractions[i - 1]);
  // after the next update the world spheres contain every level of every object, in world space
  EXPECT_EQ(scene.update(), scene.objectCount());
  const std::vector<int32_t> objects = objectNodes(s);
  const std::vector<glm::mat4> world = worldTransforms(s);
  ASSERT_EQ(scene.objectCount(), objects.size());
  for (size_t k = 0; k < objects.size(); ++k) {
    const glm::mat4& w = world[objects[k]];
    const LodChain& c = lods.chains[s.nodes[objects[k]].mesh];
    for (const LodLevel& level : c.levels)
      for (const glm::vec3& q : level.mesh.positions)
        ASSERT_LE(glm::length(glm::vec3(w * glm::vec4(q, 1.0f)) - scene.worldCenters()[k]), scene.worldRadii()[k] * (1.0f + 1e-5f));
  }
}

TEST(LodBuild, ParallelBuildEqualsOneChainAtATime) {
  const SceneData s = smallDemo();
  SceneLods lods;
  ASSERT_TRUE(buildLods(s, params(), lods).ok());
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    LodChain one;
    ASSERT_TRUE(buildChain(s.meshes[m].mesh, params().chain, one).ok());
    ASSERT_EQ(one.levelCount(), lods.chains[m].levelCount());
    for (size_t l = 0; l < one.levelCount(); ++l) {
      EXPECT_EQ(one.levels[l].mesh.positions, lods.chains[m].levels[l].mesh.positions);
      EXPECT_EQ(one.levels[l].mesh.triangles, lods.chains[m].levels[l].mesh.triangles);
      EXPECT_EQ(one.levels[l].mesh.edges, lods.chains[m].levels[l].mesh.edges);
      EXPECT_EQ(one.levels[l].cell_width, lods.chains[m].levels[l].cell_width);
    }
  }
}

TEST(LodBuild, ABadMeshIsNamedInTheError) {
  SceneData s = smallDemo();
  s.meshes[3].mesh.positions[5].x = std::numeric_limits<float>::quiet_NaN();
  SceneLods lods;
  const Error e = buildLods(s, params(), lods, nullptr, "demo.glb");
  ASSERT_FALSE(e.ok());
  EXPECT_NE(e.message.find("demo.glb mesh 3 '" + s.meshes[3].name + "'"), std::string::npos) << e.message;
}

TEST(LodBuild, RelativeFirstCellWidthFollowsEachMeshsSize) {
  const SceneData s = smallDemo();
  LodBuildParams p = params();
  p.first_cell_rel = 0.05f;
  SceneLods lods;
  ASSERT_TRUE(buildLods(s, p, lods).ok());
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    ASSERT_GE(lods.chains[m].levelCount(), 2u);
    EXPECT_FLOAT_EQ(lods.chains[m].levels[1].cell_width, 0.05f * computeBounds(s.meshes[m].mesh).diagonal()) << s.meshes[m].name;
  }
}
