#include "scenelod/scene/demo_scene.h"

#include <algorithm>
#include <map>
#include <tuple>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "scenelod/lodcore/chain.h"
#include "test_support.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

// every undirected edge (vertices welded by exact position) used by an even, non-zero number of
// triangles: the mesh is a union of closed shells
bool closedShells(const Mesh& m) {
  std::map<std::tuple<float, float, float>, uint32_t> weld;
  std::vector<uint32_t> id(m.vertexCount());
  for (size_t v = 0; v < m.vertexCount(); ++v) {
    const glm::vec3& p = m.positions[v];
    id[v] = weld.emplace(std::make_tuple(p.x, p.y, p.z), uint32_t(weld.size())).first->second;
  }
  std::map<std::pair<uint32_t, uint32_t>, int> uses;
  for (size_t t = 0; t < m.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = id[m.triangles[3 * t + k]], b = id[m.triangles[3 * t + (k + 1) % 3]];
      if (a > b) std::swap(a, b);
      ++uses[{a, b}];
    }
  for (const auto& e : uses)
    if (e.second % 2 != 0) return false;
  return true;
}

}  // namespace

TEST(DemoScene, IsDeterministicValidAndSharesMeshes) {
  DemoSceneParams p;
  p.bunny_path = "";  // the generated blob: this test must not depend on installed files
  SceneData a, b;
  DemoSceneInfo info;
  ASSERT_TRUE(makeDemoScene(a, p, &info).ok());
  ASSERT_TRUE(makeDemoScene(b, p).ok());
  EXPECT_FALSE(info.bunny_loaded);
  EXPECT_NE(info.note.find("generated organic blob"), std::string::npos) << info.note;
  EXPECT_TRUE(validateSceneData(a, "demo").ok());
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (size_t m = 0; m < a.meshes.size(); ++m) {
    EXPECT_EQ(a.meshes[m].mesh.positions, b.meshes[m].mesh.positions);
    EXPECT_EQ(a.meshes[m].mesh.triangles, b.meshes[m].mesh.triangles);
  }
  const std::vector<int32_t> objects = objectNodes(a);
  EXPECT_GE(objects.size(), 50u);
  EXPECT_LT(a.meshes.size(), objects.size() / 3);  // instances share meshes
  std::vector<int> instances(a.meshes.size(), 0);
  for (int32_t n : objects) ++instances[a.nodes[n].mesh];
  for (size_t m = 0; m < a.meshes.size(); ++m) EXPECT_GE(instances[m], 1) << a.meshes[m].name;
  EXPECT_EQ(instances.back(), 4);  // the bunny stand-in, instanced bunny_count times
}

TEST(DemoScene, PartsAreClosedShellsWithoutDegenerateTriangles) {
  DemoSceneParams p;
  p.bunny_path = "";
  SceneData s;
  ASSERT_TRUE(makeDemoScene(s, p).ok());
  for (const MeshData& md : s.meshes) {
    const Mesh& m = md.mesh;
    EXPECT_TRUE(closedShells(m)) << md.name;
    // outward winding: a closed shell wound outwards encloses a positive signed volume
    double volume = 0.0;
    for (size_t t = 0; t < m.triangleCount(); ++t)
      volume += glm::dot(glm::dvec3(m.positions[m.triangles[3 * t]]),
                         glm::cross(glm::dvec3(m.positions[m.triangles[3 * t + 1]]), glm::dvec3(m.positions[m.triangles[3 * t + 2]]))) / 6.0;
    EXPECT_GT(volume, 0.0) << md.name;
    ASSERT_EQ(m.normals.size(), m.vertexCount()) << md.name;
    ASSERT_EQ(m.colors.size(), m.vertexCount()) << md.name;
    for (size_t t = 0; t < m.triangleCount(); ++t) {
      const glm::vec3 a = m.positions[m.triangles[3 * t]], b = m.positions[m.triangles[3 * t + 1]],
                      c = m.positions[m.triangles[3 * t + 2]];
      const glm::vec3 n = glm::cross(b - a, c - a);
      ASSERT_GT(glm::length(n), 0.0f) << md.name << " triangle " << t;
      // flat faces: the stored normal agrees with the winding
      const glm::vec3 avg = m.normals[m.triangles[3 * t]] + m.normals[m.triangles[3 * t + 1]] + m.normals[m.triangles[3 * t + 2]];
      EXPECT_GT(glm::dot(n, avg), 0.0f) << md.name << " triangle " << t << " is wound against its normals";
    }
  }
}

TEST(DemoScene, HasThinPartsForThickEdges) {
  DemoSceneParams p;
  p.bunny_path = "";
  SceneData s;
  ASSERT_TRUE(makeDemoScene(s, p).ok());
  int thin = 0;
  for (const MeshData& md : s.meshes) {
    const glm::vec3 e = computeBounds(md.mesh).extent();
    const float smallest = std::min(e.x, std::min(e.y, e.z)), largest = std::max(e.x, std::max(e.y, e.z));
    if (smallest < 0.05f * largest) ++thin;  // fins and rods
  }
  EXPECT_GE(thin, 2);
}

TEST(DemoScene, UsesTheBunnyWhenInstalled) {
  SCENELOD_REQUIRE_BUNNY();
  SceneData s;
  DemoSceneInfo info;
  ASSERT_TRUE(makeDemoScene(s, {}, &info).ok());
  EXPECT_TRUE(info.bunny_loaded) << info.note;
  EXPECT_EQ(s.meshes.back().name, "bunny");
  EXPECT_EQ(s.meshes.back().mesh.vertexCount(), 34835u);
  EXPECT_EQ(s.meshes.back().mesh.triangleCount(), 69666u);
}

TEST(DemoScene, NoBunniesMeansNoBunnyMesh) {
  DemoSceneParams p;
  p.bunny_count = 0;
  SceneData s;
  DemoSceneInfo info;
  ASSERT_TRUE(makeDemoScene(s, p, &info).ok());
  EXPECT_EQ(s.meshes.size(), 11u);
  std::vector<int> instances(s.meshes.size(), 0);
  for (int32_t n : objectNodes(s)) ++instances[s.nodes[n].mesh];
  for (size_t m = 0; m < s.meshes.size(); ++m) EXPECT_GE(instances[m], 1) << s.meshes[m].name;
}

TEST(DemoScene, BadParametersAreRefused) {
  SceneData s;
  DemoSceneParams p;
  p.segments = 2;
  EXPECT_EQ(makeDemoScene(s, p).status, Status::kInvalidArgument);
  p = DemoSceneParams{};
  p.gearbox_count = 0;
  EXPECT_EQ(makeDemoScene(s, p).status, Status::kInvalidArgument);
}

// the parts are textured: uvs on every vertex, a material with a texture whose image is decoded
// (RGBA8 of its size) and encoded (PNG bytes, for exporters); a checker and a label made in code
TEST(DemoScene, PartsCarryUvsAndGeneratedTextures) {
  DemoSceneParams p;
  p.bunny_path = "";
  SceneData s;
  ASSERT_TRUE(makeDemoScene(s, p).ok());
  ASSERT_EQ(s.images.size(), 2u);
  for (const ImageData& img : s.images) {
    ASSERT_EQ(img.rgba8.size(), static_cast<size_t>(img.width) * img.height * 4) << img.name;
    ASSERT_GE(img.encoded.size(), 8u) << img.name;
    EXPECT_EQ(img.encoded[1], 'P');
    EXPECT_EQ(img.encoded[2], 'N');
    EXPECT_EQ(img.encoded[3], 'G');
    EXPECT_EQ(img.mime_type, "image/png");
    // two kinds of texel at least: a checker's two greys, a label's ink and plate
    bool light = false, dark = false;
    for (size_t i = 0; i < img.rgba8.size(); i += 4) (img.rgba8[i] > 200 ? light : dark) = true;
    EXPECT_TRUE(light && dark) << img.name;
  }
  size_t textured = 0;
  for (const MaterialData& m : s.materials) {
    EXPECT_EQ(m.base_color, glm::vec4(1.0f)) << m.name;  // the colour is in the vertex colours
    if (!m.textured) {
      EXPECT_EQ(m.base_color_texture, -1) << m.name;
      continue;
    }
    ++textured;
    ASSERT_GE(m.base_color_texture, 0) << m.name;
    ASSERT_LT(static_cast<size_t>(m.base_color_texture), s.textures.size()) << m.name;
    const TextureData& t = s.textures[static_cast<size_t>(m.base_color_texture)];
    ASSERT_GE(t.image, 0);
    ASSERT_LT(static_cast<size_t>(t.image), s.images.size());
    EXPECT_LT(m.average_texel_color.x, 1.0f);
    EXPECT_GT(m.average_texel_color.x, 0.2f);
  }
  EXPECT_GE(textured, 4u);
  int labelled = 0;
  for (const MaterialData& m : s.materials) labelled += m.textured && s.textures[m.base_color_texture].image == 1;
  EXPECT_GE(labelled, 1);
  size_t textured_meshes = 0;
  for (const MeshData& md : s.meshes) {
    // untextured parts (the banded round ones) carry no uvs, so their chains are as before
    if (!s.materials[static_cast<size_t>(md.primitive_materials[0])].textured) {
      EXPECT_TRUE(md.mesh.uvs.empty()) << md.name;
      continue;
    }
    ++textured_meshes;
    ASSERT_EQ(md.mesh.uvs.size(), md.mesh.vertexCount()) << md.name;
    EXPECT_TRUE(validateMesh(md.mesh, md.name).ok());
    // the texture repeats over the part: its uvs span more than a single texel
    glm::vec2 lo(1e30f), hi(-1e30f);
    for (const glm::vec2& uv : md.mesh.uvs) lo = glm::min(lo, uv), hi = glm::max(hi, uv);
    EXPECT_GT(std::max(hi.x - lo.x, hi.y - lo.y), 0.02f) << md.name;
    // a vertex's uv follows from its position alone: copies of a vertex never become a UV seam
    for (size_t i = 0; i < md.mesh.vertexCount(); ++i)
      for (size_t j = i + 1; j < std::min(md.mesh.vertexCount(), i + 40); ++j)
        if (md.mesh.positions[i] == md.mesh.positions[j]) EXPECT_EQ(md.mesh.uvs[i], md.mesh.uvs[j]) << md.name;
  }
  EXPECT_GE(textured_meshes, 8u);
}

// the texture coordinates change no chain: every mesh clusters into the same levels with and
// without them (what keeps the demo's selection and its recorded runs as they were)
TEST(DemoScene, TextureCoordinatesLeaveTheChainsAsTheyWere) {
  DemoSceneParams p;
  p.bunny_path = "";
  SceneData s;
  ASSERT_TRUE(makeDemoScene(s, p).ok());
  size_t compared = 0;
  for (const MeshData& md : s.meshes) {
    if (md.mesh.uvs.empty()) continue;
    Mesh plain = md.mesh;
    plain.uvs.clear();
    LodChain with, without;
    ASSERT_TRUE(buildChain(md.mesh, ChainParams(), with).ok()) << md.name;
    ASSERT_TRUE(buildChain(plain, ChainParams(), without).ok()) << md.name;
    ASSERT_EQ(with.levelCount(), without.levelCount()) << md.name;
    for (size_t k = 0; k < with.levelCount(); ++k) {
      const Mesh &a = with.levels[k].mesh, &b = without.levels[k].mesh;
      EXPECT_EQ(with.levels[k].cell_width, without.levels[k].cell_width) << md.name << " level " << k;
      EXPECT_EQ(a.triangleCount(), b.triangleCount()) << md.name << " level " << k;
      EXPECT_EQ(a.edgeCount(), b.edgeCount()) << md.name << " level " << k;
      EXPECT_EQ(a.pointCount(), b.pointCount()) << md.name << " level " << k;
      if (k > 0 && a.triangleCount()) EXPECT_EQ(a.uvs.size(), a.vertexCount()) << md.name << " keeps its uvs";
    }
    ++compared;
  }
  EXPECT_GE(compared, 8u);
}
