// `scenelod simplify --method zhang` and `scenelod lods --method zhang`, run as a user would.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "scenelod/lodcore/obj_io.h"
#include "tool_runner.h"

using namespace scenelod;

namespace {

using scenelod::test::ToolRun;
using scenelod::test::runTool;

// a closed UV sphere: 2 poles, (rings - 1) x segments vertices, 2 x segments x (rings - 1) triangles
std::string writeSphere(int rings, int segments) {
  Mesh m;
  m.positions.push_back({0, 0, 1});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const float th = 3.14159265f * r / rings, ph = 6.2831853f * s / segments;
      m.positions.push_back({std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)});
    }
  m.positions.push_back({0, 0, -1});
  const uint32_t south = static_cast<uint32_t>(m.positions.size() - 1);
  auto at = [&](int r, int s) { return static_cast<uint32_t>(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) {
    m.triangles.insert(m.triangles.end(), {0, at(1, s), at(1, s + 1)});
    m.triangles.insert(m.triangles.end(), {south, at(rings - 1, s + 1), at(rings - 1, s)});
    for (int r = 1; r + 1 < rings; ++r)
      m.triangles.insert(m.triangles.end(), {at(r, s), at(r + 1, s), at(r + 1, s + 1), at(r, s), at(r + 1, s + 1), at(r, s + 1)});
  }
  const std::string path = test::scratchDir() + "/zhang_sphere.obj";
  EXPECT_TRUE(writeObj(path, m).ok());
  return path;
}

}  // namespace

TEST(ZhangTool, SimplifyReachesTheTarget) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  const std::string in = writeSphere(24, 32);  // 1472 triangles
  const std::string out = test::scratchDir() + "/zhang_simplified.obj";
  const ToolRun r = runTool("simplify " + in + " -o " + out + " --method zhang --target-triangles 300 --zhang-placement neighbour");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("target-reached"), std::string::npos) << r.output;
  Mesh m;
  ASSERT_TRUE(readObj(out, m).ok());
  EXPECT_LE(m.triangleCount(), 300u);
  EXPECT_GE(m.triangleCount(), 298u);
  std::remove(out.c_str());
}

TEST(ZhangTool, LodsWritesHalvingLevels) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  const std::string in = writeSphere(24, 32);
  const std::string stem = test::scratchDir() + "/zhang_chain";
  const ToolRun r = runTool("lods " + in + " -o " + stem + ".obj --method zhang --levels 3 --zhang-mode triangle");
  ASSERT_EQ(r.code, 0) << r.output;
  size_t previous = 1472;
  for (int k = 1; k <= 3; ++k) {
    Mesh m;
    const std::string path = stem + "-level" + std::to_string(k) + ".obj";
    ASSERT_TRUE(readObj(path, m).ok()) << path;
    EXPECT_LE(m.triangleCount(), previous / 2) << "level " << k;
    previous = m.triangleCount();
    std::remove(path.c_str());
  }
}

TEST(ZhangTool, RefusesBadOptions) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  const std::string in = writeSphere(8, 8);
  ToolRun r = runTool("simplify " + in + " -o x.obj --method zhang --zhang-placement sideways");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("unknown --zhang-placement 'sideways'"), std::string::npos) << r.output;
  r = runTool("simplify " + in + " -o x.obj --method zhang --zhang-ring maybe");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--zhang-ring takes yes or no, not 'maybe'"), std::string::npos) << r.output;
  r = runTool("simplify " + in + " -o x.obj --method zhang --cell 0.1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--method zhang takes --target-triangles"), std::string::npos) << r.output;
  r = runTool("lods " + in + " -o x.glb --method zhang --zhang-mode triangle");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--zhang-mode needs --flatten or --split"), std::string::npos) << r.output;
  r = runTool("lods " + in + " -o x.obj --method zhang --cell-rel 0.1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("not --cell or --cell-rel"), std::string::npos) << r.output;
}
