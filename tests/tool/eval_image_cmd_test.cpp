// `scenelod eval --image` and `--at-switch`, run as a user would: the textured image error columns,
// and clear messages when the options do not fit together.
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "tool_runner.h"

namespace {

using scenelod::test::runTool;
using scenelod::test::ToolRun;

// a UV sphere of radius 1 as OBJ text (quads), fine enough to simplify into a few levels
std::string writeSphereObj(const std::string& name) {
  std::string s;
  const int rings = 16, sectors = 32;
  for (int r = 0; r <= rings; ++r)
    for (int k = 0; k < sectors; ++k) {
      const double th = M_PI * r / rings, ph = 2.0 * M_PI * k / sectors;
      s += "v " + std::to_string(std::sin(th) * std::cos(ph)) + " " + std::to_string(std::cos(th)) + " " +
           std::to_string(std::sin(th) * std::sin(ph)) + "\n";
    }
  for (int r = 0; r < rings; ++r)
    for (int k = 0; k < sectors; ++k) {
      const int a = r * sectors + k + 1, b = r * sectors + (k + 1) % sectors + 1;
      s += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(b + sectors) + " " +
           std::to_string(a + sectors) + "\n";
    }
  const std::string path = scenelod::test::scratchDir() + "/" + name;
  std::ofstream(path) << s;
  return path;
}

double jsonValue(const std::string& json, const std::string& key) {
  const size_t k = json.find("\"" + key + "\":");
  if (k == std::string::npos) return NAN;
  return std::strtod(json.c_str() + k + key.size() + 3, nullptr);
}

class EvalImageCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  }
};

TEST_F(EvalImageCommand, PairReportsTheColourErrorApartFromTheSilhouette) {
  const std::string a = writeSphereObj("sphere_a.obj");
  ToolRun r = runTool("eval " + a + " " + a + " --image --samples 1000 --resolution 32");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* word : {"silhouette mismatch", "colour off > 16/255", "colour MAD", "no textures"})
    EXPECT_NE(r.output.find(word), std::string::npos) << word << "\n" << r.output;
  r = runTool("eval " + a + " " + a + " --image --json --samples 1000 --resolution 32");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(jsonValue(r.output, "color_off"), 0.0) << r.output;
  EXPECT_EQ(jsonValue(r.output, "color_mad"), 0.0) << r.output;
  // without --image the JSON keeps its keys as before
  r = runTool("eval " + a + " " + a + " --json --samples 1000 --resolution 32");
  EXPECT_EQ(r.output.find("color_off"), std::string::npos) << r.output;
}

TEST_F(EvalImageCommand, ChainReportsEveryLevelAtItsSwitchDistance) {
  const std::string a = writeSphereObj("sphere_chain.obj");
  ToolRun r = runTool("eval " + a + " --chain --image --at-switch all --levels 3 --samples 1000 --json");
  ASSERT_EQ(r.code, 0) << r.output;
  // each level is seen at 2 r / cell width pixels: coarser levels at fewer pixels
  size_t pos = 0;
  double last = 1e9;
  int seen = 0;
  while ((pos = r.output.find("\"image_resolution\":", pos)) != std::string::npos) {
    const double px = std::strtod(r.output.c_str() + pos + 19, nullptr);
    EXPECT_LE(px, last);
    EXPECT_GE(px, 8.0);
    last = px;
    ++seen;
    ++pos;
  }
  EXPECT_EQ(seen, 3) << r.output;
  r = runTool("eval " + a + " --chain --image --at-switch 2 --levels 3 --samples 1000");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("at the level's switch distance"), std::string::npos) << r.output;
}

TEST_F(EvalImageCommand, AtSwitchNeedsAChainAndALevel) {
  const std::string a = writeSphereObj("sphere_bad.obj");
  ToolRun r = runTool("eval " + a + " " + a + " --image --at-switch 1");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--at-switch needs --chain"), std::string::npos) << r.output;
  r = runTool("eval " + a + " --chain --image --at-switch 0");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("'all'"), std::string::npos) << r.output;
  r = runTool("eval " + a + " --chain --image --at-switch 9 --levels 2 --samples 100");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("levels 0..2"), std::string::npos) << r.output;
}

}  // namespace
