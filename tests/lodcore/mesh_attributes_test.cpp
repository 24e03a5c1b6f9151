#include "scenelod/lodcore/mesh_attributes.h"

#include <cmath>
#include <set>
#include <string>

#include <gtest/gtest.h>

using namespace scenelod;

namespace {

// a unit cube written the way non-indexed exporters write it: three fresh vertices per triangle,
// each face with its own normal and the texture coordinates `uv(face, corner)` (corners 0..3
// counter-clockwise seen from outside)
template <class Uv>
Mesh nonIndexedCube(Uv uv) {
  // per face: the normal axis and sign, and the four corners
  static const int kFaces[6][4][3] = {
      {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}},  // +x
      {{0, 1, 0}, {0, 0, 0}, {0, 0, 1}, {0, 1, 1}},  // -x
      {{1, 1, 0}, {0, 1, 0}, {0, 1, 1}, {1, 1, 1}},  // +y
      {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}},  // -y
      {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},  // +z
      {{0, 1, 0}, {1, 1, 0}, {1, 0, 0}, {0, 0, 0}},  // -z
  };
  static const glm::vec3 kNormals[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  Mesh m;
  for (int f = 0; f < 6; ++f) {
    for (int c : {0, 1, 2, 0, 2, 3}) {
      const int* p = kFaces[f][c];
      m.triangles.push_back(static_cast<uint32_t>(m.positions.size()));
      m.positions.emplace_back(float(p[0]), float(p[1]), float(p[2]));
      m.normals.push_back(kNormals[f]);
      m.uvs.push_back(uv(f, c));
    }
  }
  return m;
}

// a quad of two triangles sharing the edge 0-2
Mesh quad() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.triangles = {0, 1, 2, 0, 2, 3};
  return m;
}

const glm::vec2 kCorner[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};

}  // namespace

TEST(MeshAttributes, WeldJoinsTheRepeatedVerticesOfANonIndexedMesh) {
  // every face in its own square of texture space: 4 distinct vertices per face
  Mesh m = nonIndexedCube([](int f, int c) { return kCorner[c] + glm::vec2(2.0f * f, 0.0f); });
  ASSERT_TRUE(validateMesh(m, "cube").ok());
  ASSERT_EQ(m.vertexCount(), 36u);
  std::vector<uint32_t> to;
  EXPECT_EQ(weldVertices(m, &to), 12u);
  EXPECT_EQ(m.vertexCount(), 24u);
  EXPECT_EQ(m.triangleCount(), 12u);
  EXPECT_TRUE(validateMesh(m, "welded cube").ok());
  ASSERT_EQ(to.size(), 36u);
  EXPECT_EQ(to[0], 0u);
  EXPECT_EQ(to[3], 0u);  // the second triangle's first corner is the first triangle's
  EXPECT_EQ(m.positions[to[5]], glm::vec3(1, 0, 1));
}

TEST(MeshAttributes, WeldKeepsVerticesThatDifferInAnyAttribute) {
  Mesh m;
  m.positions = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {-0.0f, 0, 0}};
  m.uvs = {{0, 0}, {0, 0.5f}, {0, 0}, {0, 0}, {0, 0}};
  m.tangents = {{1, 0, 0, 1}, {1, 0, 0, 1}, {1, 0, 0, -1}, {1, 0, 0, 1}, {1, 0, 0, 1}};
  m.joints = {{0, 1, 0, 0}, {0, 1, 0, 0}, {0, 1, 0, 0}, {0, 2, 0, 0}, {0, 1, 0, 0}};
  m.weights = std::vector<glm::vec4>(5, glm::vec4(0.5f, 0.5f, 0, 0));
  m.points = {0, 1, 2, 3, 4};
  ASSERT_TRUE(validateMesh(m, "m").ok());
  // 1: another uv; 2: another tangent sign; 3: another joint; 4: -0 equals +0, so it joins 0
  EXPECT_EQ(weldVertices(m), 1u);
  EXPECT_EQ(m.points, (std::vector<uint32_t>{0, 1, 2, 3, 0}));
}

TEST(MeshAttributes, CubeWithEveryFaceInItsOwnUvSquareHasSixCharts) {
  const Mesh m = nonIndexedCube([](int f, int c) { return kCorner[c] + glm::vec2(2.0f * f, 0.0f); });
  std::vector<uint32_t> chart;
  EXPECT_EQ(computeUvCharts(m, chart), 6u);
  for (size_t t = 0; t < m.triangleCount(); ++t) EXPECT_EQ(chart[t], t / 2) << "triangle " << t;
}

TEST(MeshAttributes, CubeUnwrappedAsAStripHasThreeCharts) {
  // the four sides (+x, +y, -x, -y going round) continuous in u from 0 to 4, cut once where u
  // returns from 4 to 0; top and bottom each in a square of their own
  auto uv = [](int f, int c) -> glm::vec2 {
    const int side_index[6] = {0, 2, 1, 3, -1, -1};
    if (side_index[f] < 0) return kCorner[c] + glm::vec2(10.0f * f, 5.0f);
    const float u0 = float(side_index[f]);
    return glm::vec2(u0 + kCorner[c].x, kCorner[c].y);
  };
  const Mesh m = nonIndexedCube(uv);
  std::vector<uint32_t> chart;
  EXPECT_EQ(computeUvCharts(m, chart), 3u);
  // the sides share a chart, top (face 4) and bottom (face 5) do not
  EXPECT_EQ(chart[0], chart[4]);   // +x and +y
  EXPECT_EQ(chart[2], chart[6]);   // -x and -y
  EXPECT_NE(chart[8], chart[0]);   // top
  EXPECT_NE(chart[10], chart[0]);  // bottom
  EXPECT_NE(chart[10], chart[8]);
}

TEST(MeshAttributes, MaterialBorderSeparatesCharts) {
  Mesh m = quad();
  std::vector<uint32_t> chart;
  EXPECT_EQ(computeUvCharts(m, chart), 1u);
  m.triangle_groups = {0, 1};
  ASSERT_TRUE(validateMesh(m, "quad").ok());
  EXPECT_EQ(computeUvCharts(m, chart), 2u);
  EXPECT_EQ(chart, (std::vector<uint32_t>{0, 1}));
}

TEST(MeshAttributes, SecondUvSetSeamSeparatesCharts) {
  Mesh m = quad();
  // split the shared edge's vertices so the second set can differ across it
  m.positions.push_back(m.positions[0]);
  m.positions.push_back(m.positions[2]);
  m.uvs.push_back(m.uvs[0]);
  m.uvs.push_back(m.uvs[2]);
  m.triangles = {0, 1, 2, 4, 5, 3};
  m.extra_uvs = {{{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}, {1, 1}}};
  std::vector<uint32_t> chart;
  EXPECT_EQ(computeUvCharts(m, chart), 1u);  // equal in both sets: one chart
  m.extra_uvs[0][4] = {0.5f, 0.5f};
  EXPECT_EQ(computeUvCharts(m, chart), 2u);
}

TEST(MeshAttributes, BadAttributesAreRefusedNamingMeshAndAttribute) {
  struct Case {
    const char* expect;
    void (*spoil)(Mesh&);
  };
  const Case cases[] = {
      {"3 texture coordinates for 4 vertices", [](Mesh& m) { m.uvs.pop_back(); }},
      {"NaN or infinite value in its texture coordinates", [](Mesh& m) { m.uvs[1].y = std::nanf(""); }},
      {"texture coordinates (set 1)", [](Mesh& m) { m.extra_uvs = {{{0, 0}}}; }},
      {"tangent sign w = 0", [](Mesh& m) { m.tangents = std::vector<glm::vec4>(4, glm::vec4(1, 0, 0, 0)); }},
      {"skin joints without weights", [](Mesh& m) { m.joints.resize(4); }},
      {"weights summing to 0",
       [](Mesh& m) {
         m.joints.resize(4);
         m.weights = std::vector<glm::vec4>(4, glm::vec4(0.0f));
       }},
      {"NaN or infinite value in its skin weights",
       [](Mesh& m) {
         m.joints.resize(4);
         m.weights = std::vector<glm::vec4>(4, glm::vec4(1, 0, 0, 0));
         m.weights[2].x = std::nanf("");
       }},
      {"uses joint 5 but the skeleton has 2 joints",
       [](Mesh& m) {
         m.joints = std::vector<glm::u16vec4>(4, glm::u16vec4(0, 5, 0, 0));
         m.weights = std::vector<glm::vec4>(4, glm::vec4(1, 0, 0, 0));
         m.joint_parents = {-1, 0};
       }},
      {"form a cycle", [](Mesh& m) { m.joint_parents = {-1, 2, 1}; }},
      {"has parent 7", [](Mesh& m) { m.joint_parents = {-1, 7}; }},
      {"1 triangle groups for 2 triangles", [](Mesh& m) { m.triangle_groups = {0}; }},
  };
  for (const Case& c : cases) {
    Mesh m = quad();
    c.spoil(m);
    const Error e = validateMesh(m, "helmet/mesh 3");
    ASSERT_FALSE(e.ok()) << c.expect;
    EXPECT_EQ(e.status, Status::kInvalidMesh);
    EXPECT_NE(e.message.find("helmet/mesh 3"), std::string::npos) << e.message;
    EXPECT_NE(e.message.find(c.expect), std::string::npos) << e.message;
  }
}
