// The scene subcommands of the scenelod tool, run as a user would: demo-scene (and pack, lods).
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "scenelod/scene/demo_scene.h"
#include "scenelod/scene/gltf_io.h"
#include "tool_runner.h"

using namespace scenelod;

namespace {

using scenelod::test::ToolRun;
using scenelod::test::runTool;

}  // namespace

TEST(SceneCommands, DemoPrintsOneRowPerMeshWithInstanceAndTriangleCounts) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  const std::string dir = scenelod::test::scratchDir() + "/demo_table";
  const ToolRun r = runTool("demo --table-only -o " + dir +
                            " --segments 8 --gearboxes 2 --bunnies 3 --bunny /nonexistent/bunny.obj");
  ASSERT_EQ(r.code, 0) << r.output;
  // the same scene built here: instances and level-0 triangles per mesh
  scene::DemoSceneParams p;
  p.segments = 8;
  p.gearbox_count = 2;
  p.bunny_count = 3;
  p.bunny_path = "/nonexistent/bunny.obj";
  scene::SceneData s;
  ASSERT_TRUE(scene::makeDemoScene(s, p).ok());
  const std::vector<int32_t> objects = scene::objectNodes(s);
  std::vector<size_t> instances(s.meshes.size(), 0);
  size_t drawn = 0;
  for (int32_t n : objects) {
    ++instances[static_cast<size_t>(s.nodes[n].mesh)];
    drawn += s.meshes[static_cast<size_t>(s.nodes[n].mesh)].mesh.triangleCount();
  }
  ASSERT_LE(s.meshes.size(), 30u);  // no mesh row is folded at this size
  std::vector<std::string> lines;
  for (size_t a = 0, b; a < r.output.size(); a = b + 1) {
    b = r.output.find('\n', a);
    if (b == std::string::npos) b = r.output.size();
    lines.push_back(r.output.substr(a, b - a));
  }
  size_t header = lines.size();
  for (size_t i = 0; i < lines.size(); ++i)
    if (lines[i].rfind("mesh  name", 0) == 0) header = i;
  ASSERT_LT(header + s.meshes.size() + 2, lines.size() + 1) << r.output;
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    char name[64];
    size_t id = 99, inst = 0, tris = 0, levels = 0;
    char objs[64];
    ASSERT_EQ(std::sscanf(lines[header + 1 + m].c_str(), "%zu %63s %zu %63s %zu %zu", &id, name, &inst, objs, &tris, &levels), 6)
        << lines[header + 1 + m];
    EXPECT_EQ(id, m);
    const std::string& full = s.meshes[m].name;
    EXPECT_EQ(std::string(name), full.size() > 14 ? full.substr(0, 13) + "~" : full);
    EXPECT_EQ(inst, instances[m]) << s.meshes[m].name;
    EXPECT_EQ(tris, s.meshes[m].mesh.triangleCount()) << s.meshes[m].name;
    EXPECT_GE(levels, 2u) << s.meshes[m].name;
  }
  EXPECT_NE(r.output.find(std::to_string(objects.size()) + " objects folded into " + std::to_string(s.meshes.size()) +
                          " mesh rows: " + std::to_string(drawn) + " triangles drawn at level 0"),
            std::string::npos)
      << r.output;
  // the full table: a header and one row per object, in object order
  const std::string csv = scenelod::test::readText(dir + "/demo_objects.csv");
  EXPECT_NE(r.output.find("per-object table (" + std::to_string(objects.size()) + " rows"), std::string::npos);
  size_t rows = 0;
  for (char c : csv) rows += c == '\n';
  EXPECT_EQ(rows, objects.size() + 1);
  EXPECT_EQ(csv.find("object,node,mesh,"), 0u);
  EXPECT_NE(csv.find("\n0,\"" + s.nodes[objects[0]].name + "\","), std::string::npos);
}

TEST(SceneCommands, DemoRefusesBadSceneOptions) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  ToolRun r = runTool("demo --table-only --segments 2 -o " + scenelod::test::scratchDir() + "/demo_bad");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--segments must be in 3..4096"), std::string::npos) << r.output;
  r = runTool("demo --table-only --gearboxes 0 -o " + scenelod::test::scratchDir() + "/demo_bad");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("--gearboxes must be in 1..1000"), std::string::npos) << r.output;
}

TEST(SceneCommands, DemoSceneWritesAGlbThatLoadsBack) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  const std::string out = scenelod::test::scratchDir() + "/demo.glb";
  const ToolRun r = runTool("demo-scene -o " + out + " --segments 8 --gearboxes 2 --bunnies 3 --bunny /nonexistent/bunny.obj");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("could not read the bunny at /nonexistent/bunny.obj"), std::string::npos) << r.output;
  scene::SceneData s;
  const Error e = scene::loadScene(out, s);
  ASSERT_TRUE(e.ok()) << e.message;
  // 1 plate + 2 x (bracket, 2 shafts, 2 gears, 4 bolts) + 6 pipes + 12 fins + 8 rods + 4 feet + 1 prism + 3 blobs
  EXPECT_EQ(scene::objectNodes(s).size(), 1u + 2u * 9u + 6u + 12u + 8u + 4u + 1u + 3u);
  EXPECT_NE(r.output.find("wrote " + out), std::string::npos) << r.output;
  std::remove(out.c_str());
}

TEST(SceneCommands, DemoSceneRefusesBadOptions) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  ToolRun r = runTool("demo-scene -o x.obj");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("the output must end in .glb"), std::string::npos) << r.output;
  r = runTool("demo-scene -o x.glb --segments 2");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--segments must be in 3..4096"), std::string::npos) << r.output;
  r = runTool("demo-scene");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("missing -o FILE.glb"), std::string::npos) << r.output;
}

TEST(SceneCommands, PackWritesALoadablePackAndCheckRefusesATruncatedOne) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  const std::string dir = scenelod::test::scratchDir();
  const std::string glb = dir + "/small.glb", pack = dir + "/small.slodpack";
  ToolRun r = runTool("demo-scene -o " + glb + " --segments 8 --gearboxes 1 --bunnies 0");
  ASSERT_EQ(r.code, 0) << r.output;
  r = runTool("pack " + glb + " -o " + pack + " --levels 3");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("load (one read + checks, best of 5)"), std::string::npos) << r.output;
  r = runTool("pack --check " + pack);
  ASSERT_EQ(r.code, 0) << r.output;
  // 1 plate + 9 gearbox parts + 6 pipes + 12 fins + 8 rods + 4 feet + 1 prism; 11 meshes x 4 levels
  EXPECT_NE(r.output.find("41 objects, 11 chains, 44 levels"), std::string::npos) << r.output;
  // cut the file in half: refused, naming the file
  FILE* f = std::fopen(pack.c_str(), "rb+");
  ASSERT_NE(f, nullptr);
  std::fseek(f, 0, SEEK_END);
  const long size = std::ftell(f);
  std::fclose(f);
  ASSERT_EQ(::truncate(pack.c_str(), size / 2), 0);
  r = runTool("pack --check " + pack);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find(pack + ": truncated"), std::string::npos) << r.output;
}

TEST(SceneCommands, LodsWritesOneGlbWithAChainPerMesh) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  const std::string dir = scenelod::test::scratchDir();
  const std::string glb = dir + "/small_lods_in.glb", out = dir + "/small_lods.glb";
  ToolRun r = runTool("demo-scene -o " + glb + " --segments 8 --gearboxes 1 --bunnies 0");
  ASSERT_EQ(r.code, 0) << r.output;
  r = runTool("lods " + glb + " -o " + out + " --levels 3");
  ASSERT_EQ(r.code, 0) << r.output;
  scene::SceneData in, back;
  ASSERT_TRUE(scene::loadScene(glb, in).ok());
  std::vector<LodChain> chains;
  const Error e = scene::importGltfLods(out, back, chains);
  ASSERT_TRUE(e.ok()) << e.message;
  EXPECT_EQ(scene::objectNodes(back).size(), scene::objectNodes(in).size());
  ASSERT_EQ(chains.size(), in.meshes.size());
  for (size_t m = 0; m < chains.size(); ++m) {
    EXPECT_EQ(chains[m].levelCount(), 4u) << in.meshes[m].name;
    EXPECT_EQ(chains[m].levels[0].mesh.triangleCount(), in.meshes[m].mesh.triangleCount());
  }
}

// --nested builds each level from the one before (other levels than --independent's), and the
// two options exclude each other and apply to clustering only
TEST(SceneCommands, LodsNestedAndIndependentLevels) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  const std::string dir = scenelod::test::scratchDir();
  const std::string glb = dir + "/nested_in.glb", nested = dir + "/nested.glb", independent = dir + "/independent.glb";
  ToolRun r = runTool("demo-scene -o " + glb + " --segments 8 --gearboxes 1 --bunnies 0");
  ASSERT_EQ(r.code, 0) << r.output;
  r = runTool("lods " + glb + " -o " + nested + " --levels 4 --nested");
  ASSERT_EQ(r.code, 0) << r.output;
  r = runTool("lods " + glb + " -o " + independent + " --levels 4 --independent");
  ASSERT_EQ(r.code, 0) << r.output;
  scene::SceneData a, b;
  std::vector<LodChain> ca, cb;
  ASSERT_TRUE(scene::importGltfLods(nested, a, ca).ok());
  ASSERT_TRUE(scene::importGltfLods(independent, b, cb).ok());
  ASSERT_EQ(ca.size(), cb.size());
  bool differ = false;
  for (size_t m = 0; m < ca.size(); ++m) {
    ASSERT_EQ(ca[m].levelCount(), cb[m].levelCount());
    for (size_t l = 2; l < ca[m].levelCount(); ++l)
      differ = differ || ca[m].levels[l].mesh.positions != cb[m].levels[l].mesh.positions;
  }
  EXPECT_TRUE(differ) << "nested and independent levels 2+ came out equal on every mesh";
  r = runTool("lods " + glb + " -o " + nested + " --nested --independent");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("give only one of --nested, --independent"), std::string::npos) << r.output;
  r = runTool("lods " + glb + " -o " + nested + " --nested --method zhang");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--nested applies to the clustering methods, not zhang"), std::string::npos) << r.output;
}

TEST(SceneCommands, InPlaceConvertThatCannotWriteKeepsItsInput) {
  // `convert x.glb x.glb` on a full disk once truncated x.glb; here a 16 KiB file-size limit (the
  // shell ignores SIGXFSZ so that the write fails with EFBIG instead of killing the tool)
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  const std::string dir = scenelod::test::scratchDir() + "/in_place";
  ::mkdir(dir.c_str(), 0755);
  const std::string glb = dir + "/x.glb";
  const ToolRun made = runTool("demo-scene -o " + glb + " --segments 8 --gearboxes 2 --bunnies 0");
  ASSERT_EQ(made.code, 0) << made.output;
  const std::string before = scenelod::test::readText(glb);
  ASSERT_GT(before.size(), 64u * 1024u);
  const std::string cmd = "trap '' XFSZ; ulimit -f 32; " + scenelod::test::shellQuote(SCENELOD_TOOL_PATH) + " convert " +
                          glb + " " + glb + " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string output;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) output.append(buf, n);
  const int status = ::pclose(p);
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 1) << output;
  EXPECT_NE(output.find(glb + ": write error"), std::string::npos) << output;
  EXPECT_EQ(scenelod::test::readText(glb), before);
  // nothing left beside it
  const ToolRun listing = runTool("info " + glb);
  EXPECT_EQ(listing.code, 0) << listing.output;
  FILE* ls = ::popen(("ls -A " + dir).c_str(), "r");
  std::string names;
  while ((n = std::fread(buf, 1, sizeof buf, ls)) > 0) names.append(buf, n);
  ::pclose(ls);
  EXPECT_EQ(names, "x.glb\n");
}
