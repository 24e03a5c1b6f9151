// Every model of ../shared/models read through importGltf, checked against the counts in that
// folder's README.md table (made there by an independent JSON script), which this test parses.
#include <dirent.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "scenelod/scene/gltf_io.h"
#include "test_support.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

struct ReadmeRow {
  std::string model;  // folder name
  std::map<std::string, uint64_t> counts;  // column header -> number
};

std::vector<std::string> splitRow(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  std::getline(ss, cell, '|');  // before the first '|'
  while (std::getline(ss, cell, '|')) {
    const size_t b = cell.find_first_not_of(' '), e = cell.find_last_not_of(' ');
    cells.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
  }
  return cells;
}

bool parseCount(const std::string& s, uint64_t& out) {
  std::string digits;
  for (char c : s)
    if (c != ',') digits += c;
  if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) return false;
  out = std::stoull(digits);
  return true;
}

std::vector<ReadmeRow> readReadmeTable(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::vector<std::string> header;
  std::vector<ReadmeRow> rows;
  while (std::getline(f, line)) {
    if (line.rfind("| Model |", 0) == 0) {
      header = splitRow(line);
      continue;
    }
    if (header.empty() || line.empty() || line[0] != '|' || line.rfind("|---", 0) == 0) continue;
    const std::vector<std::string> cells = splitRow(line);
    ReadmeRow row;
    row.model = cells[0].substr(0, cells[0].find(' '));
    for (size_t i = 1; i < cells.size() && i < header.size(); ++i) {
      uint64_t v;
      if (parseCount(cells[i], v)) row.counts[header[i]] = v;
    }
    rows.push_back(row);
  }
  return rows;
}

std::string modelFile(const std::string& folder) {
  DIR* d = ::opendir(folder.c_str());
  if (!d) return "";
  std::string found;
  while (dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name.size() > 4 && (name.compare(name.size() - 4, 4, ".glb") == 0 || name.compare(name.size() - 5, 5, ".gltf") == 0)) found = folder + "/" + name;
  }
  ::closedir(d);
  return found;
}

}  // namespace

TEST(SharedModels, CountsMatchTheReadmeTable) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  const std::vector<ReadmeRow> rows = readReadmeTable(test::sharedModelsDir() + "/README.md");
  ASSERT_EQ(rows.size(), 8u) << "the README table should list the 8 shared models";
  for (const ReadmeRow& row : rows) {
    SCOPED_TRACE(row.model);
    const std::string file = modelFile(test::sharedModelsDir() + "/" + row.model);
    ASSERT_FALSE(file.empty());
    SceneData s;
    const Error e = importGltf(file, s);
    ASSERT_TRUE(e.ok()) << e.message;
    uint64_t drawn = 0, unique = 0, vertices = 0, primitives = 0;
    for (int32_t node : objectNodes(s)) drawn += s.meshes[static_cast<size_t>(s.nodes[static_cast<size_t>(node)].mesh)].mesh.triangleCount();
    for (const MeshData& m : s.meshes) {
      unique += m.mesh.triangleCount();
      vertices += m.mesh.vertexCount();
      primitives += m.primitive_materials.size();
    }
    EXPECT_EQ(s.nodes.size(), row.counts.at("Nodes"));
    EXPECT_EQ(s.meshes.size(), row.counts.at("Meshes"));
    EXPECT_EQ(primitives, row.counts.at("Primitives"));
    EXPECT_EQ(drawn, row.counts.at("Triangles (drawn)"));
    EXPECT_EQ(unique, row.counts.at("Triangles (unique)"));
    EXPECT_EQ(vertices, row.counts.at("Vertices"));
    EXPECT_EQ(s.materials.size(), row.counts.at("Materials"));
    EXPECT_TRUE(validateSceneData(s, file).ok());
  }
}

TEST(SharedModels, TexturedModelsGetAnAverageTexelColour) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  SceneData s;
  const std::string file = test::sharedModelsDir() + "/Duck/Duck.glb";
  ASSERT_TRUE(importGltf(file, s).ok());
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_TRUE(s.materials[0].textured);
  // the duck is yellow: red and green well above blue, all in [0, 1]
  const glm::vec3 c = s.materials[0].average_texel_color;
  EXPECT_GT(c.r, 2.0f * c.b);
  EXPECT_GT(c.g, 1.5f * c.b);
  EXPECT_LE(c.r, 1.0f);
  EXPECT_GE(c.b, 0.0f);
  EXPECT_EQ(bakedMaterialColors(s, s.meshes[0]).size(), s.meshes[0].mesh.vertexCount());
}

namespace {

SceneData importShared(const std::string& relative) {
  SceneData s;
  const std::string file = test::sharedModelsDir() + "/" + relative;
  const Error e = importGltf(file, s);
  EXPECT_TRUE(e.ok()) << e.message;
  return s;
}

// every material's base colour texture has its image decoded, and every mesh has UVs
void expectTexturedAndDecoded(const SceneData& s) {
  size_t textured = 0;
  for (const MaterialData& m : s.materials) {
    if (m.base_color_texture < 0) continue;
    ++textured;
    const ImageData& img = s.images[static_cast<size_t>(s.textures[static_cast<size_t>(m.base_color_texture)].image)];
    EXPECT_FALSE(img.encoded.empty());
    EXPECT_TRUE(img.mime_type == "image/png" || img.mime_type == "image/jpeg") << img.mime_type;
    EXPECT_GT(img.width, 0);
    EXPECT_EQ(img.rgba8.size(), size_t(img.width) * size_t(img.height) * 4);
  }
  EXPECT_GT(textured, 0u);
  for (const MeshData& md : s.meshes) EXPECT_EQ(md.mesh.uvs.size(), md.mesh.vertexCount()) << md.name;
}

// skinned: joints and weights on every vertex, one skin, animations, a skeleton, the skinned node
// drawn in its bind pose (identity world transform)
void expectSkinnedAndAnimated(const SceneData& s) {
  ASSERT_EQ(s.skins.size(), 1u);
  EXPECT_FALSE(s.animations.empty());
  for (const AnimationData& a : s.animations) EXPECT_FALSE(a.channels.empty());
  const std::vector<glm::mat4> world = worldTransforms(s);
  size_t skinned_nodes = 0;
  for (size_t i = 0; i < s.nodes.size(); ++i) {
    if (s.nodes[i].skin < 0 || s.nodes[i].mesh < 0) continue;
    ++skinned_nodes;
    EXPECT_EQ(world[i], glm::mat4(1.0f));
    const Mesh& m = s.meshes[static_cast<size_t>(s.nodes[i].mesh)].mesh;
    EXPECT_EQ(m.joints.size(), m.vertexCount());
    EXPECT_EQ(m.weights.size(), m.vertexCount());
    EXPECT_EQ(m.joint_parents.size(), s.skins[0].joints.size());
    EXPECT_EQ(std::count(m.joint_parents.begin(), m.joint_parents.end(), -1), 1);  // one root joint
  }
  EXPECT_GT(skinned_nodes, 0u);
}

}  // namespace

TEST(SharedModels, DuckAndHelmetHaveUvsAndDecodedTextures) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  for (const char* file : {"Duck/Duck.glb", "DamagedHelmet/DamagedHelmet.glb"}) {
    SCOPED_TRACE(file);
    const SceneData s = importShared(file);
    expectTexturedAndDecoded(s);
    EXPECT_TRUE(s.meshes[0].mesh.colors.empty());  // no COLOR_0: the material is kept, not baked
  }
}

TEST(SharedModels, SheenClothHasTangents) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  const SceneData s = importShared("SheenCloth/SheenCloth.gltf");
  expectTexturedAndDecoded(s);
  for (const MeshData& md : s.meshes) {
    ASSERT_EQ(md.mesh.tangents.size(), md.mesh.vertexCount()) << md.name;
    for (const glm::vec4& t : md.mesh.tangents) ASSERT_NEAR(glm::length(glm::vec3(t)), 1.0f, 1e-2f);
  }
}

TEST(SharedModels, FoxAndBrainStemHaveSkinsAndAnimations) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  for (const char* file : {"Fox/Fox.glb", "BrainStem/BrainStem.glb"}) {
    SCOPED_TRACE(file);
    expectSkinnedAndAnimated(importShared(file));
  }
  EXPECT_EQ(importShared("Fox/Fox.glb").animations.size(), 3u);
}

TEST(SharedModels, SheenChairHasTextureTransformsAndTwoUvSets) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  const SceneData s = importShared("SheenChair/SheenChair.gltf");
  expectTexturedAndDecoded(s);
  size_t transformed = 0, second_set = 0;
  for (const MaterialData& m : s.materials)
    transformed += m.base_color_transform.scale != glm::vec2(1.0f) || m.base_color_transform.offset != glm::vec2(0.0f) ||
                   m.base_color_transform.rotation != 0.0f;
  for (const MeshData& md : s.meshes) second_set += md.mesh.extra_uvs.size() == 1 && md.mesh.extra_uvs[0].size() == md.mesh.vertexCount();
  EXPECT_GT(transformed, 0u);
  EXPECT_GT(second_set, 0u);
}
