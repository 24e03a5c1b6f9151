// `scenelod simplify|lods --method scrooge`, run as a separate process (SCENELOD_TOOL_PATH).
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "scenelod/lodcore/obj_io.h"
#include "test_support.h"

using namespace scenelod;

namespace {

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

std::string readText(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

RunResult runTool(const std::vector<std::string>& args) {
  const std::string dir = test::scratchDir();
  std::string cmd = quote(SCENELOD_TOOL_PATH);
  for (const std::string& a : args) cmd += " " + quote(a);
  cmd += " >" + dir + "/scrooge_out.txt 2>" + dir + "/scrooge_err.txt";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = readText(dir + "/scrooge_out.txt");
  r.err = readText(dir + "/scrooge_err.txt");
  return r;
}

// the 12-sided hub of SCROOGE Fig. 5 as an OBJ with polygon faces
std::string writeHub() {
  Mesh m;
  const float pi = 3.14159265f;
  for (int z = 0; z < 2; ++z)
    for (int i = 0; i < 12; ++i) m.positions.push_back({std::cos(i * pi / 6), std::sin(i * pi / 6), 0.5f * z});
  m.face_offsets.push_back(0);
  for (int i = 0; i < 12; ++i) m.face_corners.push_back(uint32_t((12 - i) % 12));
  m.face_offsets.push_back(12);
  for (uint32_t i = 0; i < 12; ++i) {
    m.face_corners.insert(m.face_corners.end(), {i, (i + 1) % 12, 12 + (i + 1) % 12, 12 + i});
    m.face_offsets.push_back(uint32_t(m.face_corners.size()));
  }
  for (uint32_t i = 0; i < 12; ++i) m.face_corners.push_back(12 + i);
  m.face_offsets.push_back(uint32_t(m.face_corners.size()));
  triangulateFaces(m);
  const std::string path = test::scratchDir() + "/hub.obj";
  EXPECT_TRUE(writeObj(path, m).ok());
  return path;
}

}  // namespace

TEST(ScroogeTool, SimplifyReducesTheHubBaseToAHexagon) {
  const std::string in = writeHub(), out = test::scratchDir() + "/hub_scrooge.obj";
  const RunResult r = runTool({"simplify", in, "-o", out, "--method", "scrooge", "--subvolume", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("method scrooge"), std::string::npos) << r.out;
  Mesh m;
  ASSERT_TRUE(readObj(out, m).ok());
  size_t hexagons = 0;
  for (size_t f = 0; f < m.faceCount(); ++f) {
    bool base = true;
    for (size_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) base = base && m.positions[m.face_corners[c]].z == 0.0f;
    if (base && m.face_offsets[f + 1] - m.face_offsets[f] == 6) ++hexagons;
  }
  EXPECT_EQ(hexagons, 1u);
}

TEST(ScroogeTool, LodsBuildsThePapersThreeSizes) {
  const std::string in = writeHub(), out = test::scratchDir() + "/hub_lods.obj";
  const RunResult r = runTool({"lods", in, "-o", out, "--method", "scrooge", "--subvolume", "1/64", "--levels", "3"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (int k = 1; k <= 3; ++k) {
    Mesh m;
    EXPECT_TRUE(readObj(test::scratchDir() + "/hub_lods-level" + std::to_string(k) + ".obj", m).ok()) << k;
    EXPECT_GT(m.triangleCount(), 0u);
  }
  EXPECT_NE(r.out.find("method scrooge"), std::string::npos) << r.out;
}

TEST(ScroogeTool, BadOptionsAreRefused) {
  const std::string in = writeHub(), out = test::scratchDir() + "/hub_bad.obj";
  RunResult r = runTool({"simplify", in, "-o", out, "--method", "scrooge", "--subvolume", "1/3"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--subvolume must be 1/64, 1/8 or 1"), std::string::npos) << r.err;
  r = runTool({"simplify", in, "-o", out, "--subvolume", "1/8"});  // clustering has no sub-volumes
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("need --method scrooge"), std::string::npos) << r.err;
  r = runTool({"simplify", in, "-o", out, "--method", "scrooge", "--cell-rel", "0.1", "--subvolume", "1"});
  EXPECT_NE(r.exit_code, 0);
  r = runTool({"simplify", in, "-o", out, "--method", "scrooge", "--theta-max", "2"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--theta-max"), std::string::npos) << r.err;
  r = runTool({"simplify", in, "-o", out, "--method", "scrooge", "--target-triangles", "10"});
  EXPECT_NE(r.exit_code, 0);
  r = runTool({"simplify", test::scratchDir() + "/missing.obj", "-o", out, "--method", "scrooge"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("missing.obj"), std::string::npos) << r.err;
}
