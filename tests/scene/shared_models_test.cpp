// Every model of ../shared/models read through importGltf, checked against the counts in that
// folder's README.md table (made there by an independent JSON script), which this test parses.
#include <dirent.h>

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
  ASSERT_EQ(s.meshes[0].mesh.colors.size(), s.meshes[0].mesh.vertexCount());
}
