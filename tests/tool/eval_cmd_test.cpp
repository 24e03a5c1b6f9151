// The eval and render subcommands, run as a user would: numbers on known inputs and clear messages
// on bad ones.
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <sys/wait.h>

#include <gtest/gtest.h>

#include "tool_runner.h"

namespace {

using Result = scenelod::test::ToolRun;
using scenelod::test::runTool;

// a box [lo, hi]^3 as OBJ text
std::string boxObj(double lo, double hi) {
  std::string s;
  for (int i = 0; i < 8; ++i)
    s += "v " + std::to_string((i & 1) ? hi : lo) + " " + std::to_string((i & 2) ? hi : lo) + " " +
         std::to_string((i & 4) ? hi : lo) + "\n";
  s += "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  return s;
}

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = scenelod::test::scratchDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

double jsonValue(const std::string& json, const std::string& key) {
  const size_t k = json.find("\"" + key + "\":");
  if (k == std::string::npos) return NAN;
  return std::strtod(json.c_str() + k + key.size() + 3, nullptr);
}

class EvalCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  }
};

// the unit cube against the cube scaled by 1.01 about its centre: Hausdorff 0.005 of the diagonal
// (see tests/eval/metrics_test.cpp for the derivation)
TEST_F(EvalCommand, JsonHasTheKnownHausdorff) {
  const std::string a = writeFile("cube.obj", boxObj(0.0, 1.0));
  const std::string b = writeFile("cube101.obj", boxObj(-0.005, 1.005));
  const Result r = runTool("eval " + a + " " + b + " --json --samples 20000 --resolution 64");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NEAR(jsonValue(r.output, "hausdorff"), 0.005, 1e-5) << r.output;
  EXPECT_GT(jsonValue(r.output, "rms"), 0.0);
  EXPECT_GT(jsonValue(r.output, "silhouette"), 0.0);
  EXPECT_LT(jsonValue(r.output, "silhouette"), 0.1);
  EXPECT_GE(jsonValue(r.output, "normal_deg"), 0.0);
  EXPECT_EQ(r.output.front(), '{');
}

TEST_F(EvalCommand, TableNamesEveryNumber) {
  const std::string a = writeFile("cube.obj", boxObj(0.0, 1.0));
  const Result r = runTool("eval " + a + " " + a + " --samples 1000 --resolution 32");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* word : {"hausdorff", "rms", "silhouette mismatch", "normal deviation"})
    EXPECT_NE(r.output.find(word), std::string::npos) << word << "\n" << r.output;
}

TEST_F(EvalCommand, BadInputGivesClearMessages) {
  const std::string cube = writeFile("cube.obj", boxObj(0.0, 1.0));
  Result r = runTool("eval /nonexistent/a.obj " + cube);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("/nonexistent/a.obj"), std::string::npos) << r.output;

  const std::string lines = writeFile("lines.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2\nl 2 3\n");
  r = runTool("eval " + lines + " " + cube);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("no triangles"), std::string::npos) << r.output;

  const std::string huge = writeFile("huge.obj", boxObj(0.0, 100.0));
  r = runTool("eval " + cube + " " + huge);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("not at the same scale"), std::string::npos) << r.output;
  r = runTool("eval " + cube + " " + huge + " --force --samples 1000 --resolution 16");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("warning"), std::string::npos) << r.output;

  r = runTool("eval " + cube);
  EXPECT_EQ(r.code, 2);
  r = runTool("eval " + cube + " " + cube + " --samples x");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--samples"), std::string::npos) << r.output;
}

TEST_F(EvalCommand, RenderWritesAPng) {
  const std::string cube = writeFile("cube.obj", boxObj(0.0, 1.0));
  const std::string png = scenelod::test::scratchDir() + "/cube.png";
  Result r = runTool("render " + cube + " -o " + png + " --view axis 4 --size 64 48");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(scenelod::test::fileExists(png));
  EXPECT_NE(r.output.find("64x48"), std::string::npos) << r.output;

  r = runTool("render " + cube + " -o " + png + " --view side 1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--view"), std::string::npos) << r.output;
  r = runTool("render " + cube + " -o /nonexistent/dir/x.png --size 32 32");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("/nonexistent/dir/x.png"), std::string::npos) << r.output;
}

// a sphere-like blob fine enough to give a chain: an icosahedron's faces, subdivided, as OBJ
std::string sphereObj(int levels) {
  std::vector<std::array<double, 3>> v;
  std::vector<std::array<int, 3>> f;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const double base[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& b : base) {
    const double l = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    v.push_back({b[0] / l, b[1] / l, b[2] / l});
  }
  const int faces[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                            {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                            {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (auto& x : faces) f.push_back({x[0], x[1], x[2]});
  for (int l = 0; l < levels; ++l) {
    std::vector<std::array<int, 3>> g;
    for (auto& x : f) {
      int m[3];
      for (int k = 0; k < 3; ++k) {
        const auto& a = v[x[k]];
        const auto& b = v[x[(k + 1) % 3]];
        std::array<double, 3> c{a[0] + b[0], a[1] + b[1], a[2] + b[2]};
        const double n = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        v.push_back({c[0] / n, c[1] / n, c[2] / n});  // duplicates are harmless for this test
        m[k] = static_cast<int>(v.size() - 1);
      }
      g.push_back({x[0], m[0], m[2]});
      g.push_back({x[1], m[1], m[0]});
      g.push_back({x[2], m[2], m[1]});
      g.push_back({m[0], m[1], m[2]});
    }
    f.swap(g);
  }
  std::string s;
  for (auto& p : v) s += "v " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
  for (auto& x : f)
    s += "f " + std::to_string(x[0] + 1) + " " + std::to_string(x[1] + 1) + " " + std::to_string(x[2] + 1) + "\n";
  return s;
}

TEST_F(EvalCommand, ChainReportsOnePoppingNumberPerTransition) {
  const std::string sphere = writeFile("sphere.obj", sphereObj(4));
  const Result r = runTool("eval " + sphere + " --chain --levels 3 --samples 2000 --json");
  ASSERT_EQ(r.code, 0) << r.output;
  size_t levels = 0, pops = 0;
  for (size_t k = r.output.find("\"level\":"); k != std::string::npos; k = r.output.find("\"level\":", k + 1)) ++levels;
  for (size_t k = r.output.find("\"from\":"); k != std::string::npos; k = r.output.find("\"from\":", k + 1)) ++pops;
  EXPECT_EQ(levels, 4u) << r.output;
  EXPECT_EQ(pops, 3u) << r.output;
}

TEST_F(EvalCommand, RenderGridLaysOutEveryLevel) {
  const std::string sphere = writeFile("sphere.obj", sphereObj(3));
  const std::string png = scenelod::test::scratchDir() + "/grid.png";
  const Result r = runTool("render " + sphere + " -o " + png + " --grid --levels 2 --size 64 64");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(scenelod::test::fileExists(png));
  EXPECT_NE(r.output.find("3 levels"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("level 2:"), std::string::npos) << r.output;
}

}  // namespace
