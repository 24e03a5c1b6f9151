// The scene subcommands of the scenelod tool, run as a user would: demo-scene (and pack, lods).
#include <cstdio>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "scenelod/scene/gltf_io.h"
#include "test_support.h"

using namespace scenelod;

namespace {

struct ToolRun {
  int code = -1;
  std::string output;  // stdout and stderr
};

ToolRun runTool(const std::string& args) {
  ToolRun r;
  const std::string cmd = std::string(SCENELOD_TOOL_PATH) + " " + args + " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.output.append(buf, n);
  const int status = ::pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

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
