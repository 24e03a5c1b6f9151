// The scenelod tool's info and convert subcommands, run as a separate process (SCENELOD_TOOL_PATH).
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "scenelod/lodcore/obj_io.h"
#include "tool_runner.h"

using namespace scenelod;

namespace {

using RunResult = scenelod::test::ToolOutput;
using scenelod::test::readText;

RunResult runTool(const std::vector<std::string>& args) { return scenelod::test::runToolSeparate(args, "info"); }

// the integer value of "key": in a one-line JSON object; -1 when absent
long long jsonInt(const std::string& json, const std::string& key) {
  const std::string k = "\"" + key + "\": ";
  const size_t at = json.find(k);
  if (at == std::string::npos) return -1;
  return std::atoll(json.c_str() + at + k.size());
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

// counts lines starting with `prefix` (e.g. "v ", "f ") in a text file
size_t countLines(const std::string& path, const std::string& prefix) {
  std::ifstream f(path);
  std::string line;
  size_t n = 0;
  while (std::getline(f, line))
    if (line.compare(0, prefix.size(), prefix) == 0) ++n;
  return n;
}

}  // namespace

TEST(ToolInfo, HelpListsTheOptions) {
  const RunResult r = runTool({"info", "--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(contains(r.out, "usage: scenelod info FILE")) << r.out;
  EXPECT_TRUE(contains(r.out, "--json")) << r.out;
  EXPECT_TRUE(contains(r.out, "-o, --out")) << r.out;
  const RunResult c = runTool({"convert", "-h"});
  EXPECT_EQ(c.exit_code, 0);
  EXPECT_TRUE(contains(c.out, "usage: scenelod convert IN OUT")) << c.out;
  EXPECT_TRUE(contains(c.out, "world space")) << c.out;
}

TEST(ToolInfo, ReadsTheBunny) {
  SCENELOD_REQUIRE_BUNNY();
  const RunResult r = runTool({"info", test::bunnyPath(), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // one vertex per 'v' line and one triangle per 'f' line (every face of the bunny is a triangle)
  EXPECT_EQ(jsonInt(r.out, "vertices"), static_cast<long long>(countLines(test::bunnyPath(), "v ")));
  EXPECT_EQ(jsonInt(r.out, "triangles"), static_cast<long long>(countLines(test::bunnyPath(), "f ")));
  EXPECT_EQ(jsonInt(r.out, "nodes"), 1);
  EXPECT_EQ(jsonInt(r.out, "meshes"), 1);
  EXPECT_EQ(jsonInt(r.out, "objects"), 1);
  EXPECT_TRUE(contains(r.out, "\"bounds\": {\"min\": [")) << r.out;
}

TEST(ToolInfo, SharedModelsMatchTheReadmeTable) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  // model folder -> (file, columns of the README table)
  std::ifstream f(test::sharedModelsDir() + "/README.md");
  std::string line;
  std::vector<std::string> header;
  int checked = 0;
  while (std::getline(f, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    std::getline(ss, cell, '|');
    while (std::getline(ss, cell, '|')) {
      const size_t b = cell.find_first_not_of(' '), e = cell.find_last_not_of(' ');
      cells.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
    }
    if (line.rfind("| Model |", 0) == 0) {
      header = cells;
      continue;
    }
    if (header.empty() || line.rfind("|---", 0) == 0 || line.empty() || line[0] != '|') continue;
    std::map<std::string, long long> col;
    for (size_t i = 0; i < cells.size() && i < header.size(); ++i) {
      std::string digits;
      for (char c : cells[i])
        if (c != ',') digits += c;
      if (!digits.empty() && digits.find_first_not_of("0123456789") == std::string::npos) col[header[i]] = std::atoll(digits.c_str());
    }
    const std::string model = cells[0].substr(0, cells[0].find(' '));
    const std::string format = cells[3];
    const std::string file = test::sharedModelsDir() + "/" + model + "/" + model + (format == ".glb" ? ".glb" : ".gltf");
    SCOPED_TRACE(file);
    const RunResult r = runTool({"info", file, "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(jsonInt(r.out, "nodes"), col.at("Nodes"));
    EXPECT_EQ(jsonInt(r.out, "meshes"), col.at("Meshes"));
    EXPECT_EQ(jsonInt(r.out, "triangles"), col.at("Triangles (drawn)"));
    EXPECT_EQ(jsonInt(r.out, "unique_triangles"), col.at("Triangles (unique)"));
    EXPECT_EQ(jsonInt(r.out, "unique_vertices"), col.at("Vertices"));
    ++checked;
  }
  EXPECT_EQ(checked, 8);
}

TEST(ToolInfo, OutOptionWritesTheReport) {
  const std::string dir = test::scratchDir();
  std::ofstream(dir + "/tri_info.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 2 2\nf 1 2 3\nl 1 4\np 4\n";
  const RunResult a = runTool({"info", dir + "/tri_info.obj", "--json", "-o", dir + "/a.json"});
  const RunResult b = runTool({"info", dir + "/tri_info.obj", "--json", "--out", dir + "/b.json"});
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const std::string ja = readText(dir + "/a.json");
  EXPECT_EQ(ja, readText(dir + "/b.json"));
  EXPECT_EQ(jsonInt(ja, "vertices"), 4);
  EXPECT_EQ(jsonInt(ja, "triangles"), 1);
  EXPECT_EQ(jsonInt(ja, "edges"), 1);
  EXPECT_EQ(jsonInt(ja, "points"), 1);
}

TEST(ToolInfo, BadInputFailsWithTheFileNamed) {
  const RunResult r = runTool({"info", "/nonexistent/x.glb"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(contains(r.err, "scenelod info: /nonexistent/x.glb: cannot open file")) << r.err;
  const RunResult u = runTool({"info"});
  EXPECT_EQ(u.exit_code, 2);
  EXPECT_TRUE(contains(u.err, "expected exactly one FILE")) << u.err;
  const RunResult o = runTool({"info", "a.obj", "--bogus"});
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_TRUE(contains(o.err, "unknown option --bogus")) << o.err;
}

TEST(ToolConvert, ObjToGlbToObjKeepsTheGeometry) {
  const std::string dir = test::scratchDir();
  std::ofstream(dir + "/conv.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 3 3 3\nf 1 2 3 4\n#t 0.5\nl 4 5\np 5\n";
  RunResult r = runTool({"convert", dir + "/conv.obj", dir + "/conv.glb"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = runTool({"info", dir + "/conv.glb", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(jsonInt(r.out, "vertices"), 5);
  EXPECT_EQ(jsonInt(r.out, "triangles"), 2);  // the quad, triangulated (glTF has no polygons)
  EXPECT_EQ(jsonInt(r.out, "edges"), 1);
  EXPECT_EQ(jsonInt(r.out, "points"), 1);
  r = runTool({"convert", dir + "/conv.glb", "-o", dir + "/back.obj"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Mesh a, b;
  ASSERT_TRUE(readObj(dir + "/conv.obj", a).ok());
  ASSERT_TRUE(readObj(dir + "/back.obj", b).ok());
  EXPECT_EQ(b.positions, a.positions);
  EXPECT_EQ(b.triangles, a.triangles);
  EXPECT_EQ(b.edges, a.edges);
  EXPECT_EQ(b.edge_thickness, a.edge_thickness);
  EXPECT_EQ(b.points, a.points);
}

TEST(ToolConvert, RefusesUnknownOutputAndBadInput) {
  const std::string dir = test::scratchDir();
  RunResult r = runTool({"convert", dir + "/whatever.obj", dir + "/out.ply"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.err, "the output must end in .glb or .obj")) << r.err;
  std::ofstream(dir + "/broken.obj") << "v 0 0 0\nf 1 2 3\n";
  r = runTool({"convert", dir + "/broken.obj", dir + "/out.glb"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(contains(r.err, dir + "/broken.obj:2: vertex index 2 out of range")) << r.err;
  r = runTool({"convert", dir + "/only_in.obj"});
  EXPECT_EQ(r.exit_code, 2);
}

TEST(ToolInfo, ListsMaterialsSkinsAndAttributesPerObject) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  // the Fox: one skinned mesh with one textured material and three animations (Survey, Walk, Run)
  const RunResult r = runTool({"info", test::sharedModelsDir() + "/Fox/Fox.glb", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(jsonInt(r.out, "objects"), 1) << r.out;
  EXPECT_EQ(jsonInt(r.out, "materials"), 1) << r.out;
  EXPECT_EQ(jsonInt(r.out, "textures"), 1) << r.out;
  EXPECT_EQ(jsonInt(r.out, "images"), 1) << r.out;
  EXPECT_EQ(jsonInt(r.out, "skins"), 1) << r.out;
  EXPECT_EQ(jsonInt(r.out, "animations"), 3) << r.out;
  EXPECT_TRUE(contains(r.out, "\"attributes\": [\"uv0\", \"skin_weights\"]")) << r.out;
  EXPECT_TRUE(contains(r.out, "\"skin\": 0")) << r.out;
  const RunResult text = runTool({"info", test::sharedModelsDir() + "/Fox/Fox.glb"});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_TRUE(contains(text.out, "skin:       0 ")) << text.out;
  EXPECT_TRUE(contains(text.out, "levels:     1 (576 triangles)")) << text.out;
}

TEST(ToolInfo, ListsTheLevelsScenelodLodsWrote) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  const std::string out = ::testing::TempDir() + "info_duck_lods.glb";
  const RunResult lods = runTool({"lods", test::sharedModelsDir() + "/Duck/Duck.glb", "-o", out, "--levels", "3"});
  ASSERT_EQ(lods.exit_code, 0) << lods.err;
  const RunResult r = runTool({"info", out, "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // one object: the original and three levels, each coarser than the one before
  const size_t at = r.out.find("\"level_triangles\": [");
  ASSERT_NE(at, std::string::npos) << r.out;
  std::istringstream in(r.out.substr(at + 20));
  std::vector<long long> tris;
  for (long long n; in >> n;) {
    tris.push_back(n);
    char sep = 0;
    if (!(in >> sep) || sep != ',') break;
  }
  ASSERT_EQ(tris.size(), 4u) << r.out;
  EXPECT_EQ(tris[0], 4212);
  for (size_t k = 1; k < tris.size(); ++k) EXPECT_LT(tris[k], tris[k - 1]) << "level " << k;
  std::remove(out.c_str());
}
