// The scene subcommands of the scenelod tool, run as a user would: demo-scene (and pack, lods).
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "scenelod/scene/gltf_io.h"
#include "tool_runner.h"

using namespace scenelod;

namespace {

using scenelod::test::ToolRun;
using scenelod::test::runTool;

}  // namespace

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
