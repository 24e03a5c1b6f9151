#include "scenelod/lodcore/obj_io.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"

using namespace scenelod;

namespace {

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = test::scratchDir() + "/" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace

TEST(ObjIo, ReadsTrianglesInFileOrder) {
  const std::string path = writeFile("tri.obj", "# a comment\no thing\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                                "s off\nf 1 2 3\nf 1 3 4\n");
  Mesh m;
  ASSERT_TRUE(readObj(path, m).ok());
  ASSERT_EQ(m.vertexCount(), 4u);
  EXPECT_EQ(m.positions[1], glm::vec3(1, 0, 0));
  EXPECT_EQ(m.triangles, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(m.faceCount(), 0u);  // no polygons: no face list
  EXPECT_TRUE(m.normals.empty());
  EXPECT_TRUE(m.uvs.empty());
}

TEST(ObjIo, KeepsPolygonsAndTriangulatesThem) {
  // a quad and a concave L-shaped hexagon in the z=0 plane, counter-clockwise
  const std::string path = writeFile("poly.obj",
                                     "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                     "v 2 0 0\nv 4 0 0\nv 4 1 0\nv 3 1 0\nv 3 3 0\nv 2 3 0\n"
                                     "f 1 2 3 4\nf 5 6 7 8 9 10\n");
  Mesh m;
  ASSERT_TRUE(readObj(path, m).ok());
  ASSERT_EQ(m.faceCount(), 2u);
  EXPECT_EQ(m.face_offsets, (std::vector<uint32_t>{0, 4, 10}));
  EXPECT_EQ(m.face_corners, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
  EXPECT_EQ(m.triangleCount(), 2u + 4u);
  // the triangulation covers each polygon's area exactly (quad 1, L shape 2 + 2 = 4) with ccw triangles
  double area = 0.0;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const glm::vec3 a = m.positions[m.triangles[3 * t]], b = m.positions[m.triangles[3 * t + 1]],
                    c = m.positions[m.triangles[3 * t + 2]];
    const double z = 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
    EXPECT_GT(z, 0.0) << "triangle " << t;
    area += z;
  }
  EXPECT_NEAR(area, 5.0, 1e-6);
}

TEST(ObjIo, ResolvesNegativeIndices) {
  const std::string path = writeFile("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 1 1 0\nf -3 -1 -2\n");
  Mesh m;
  ASSERT_TRUE(readObj(path, m).ok());
  EXPECT_EQ(m.triangles, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2}));
}

TEST(ObjIo, UnifiesPositionTexcoordNormalTriples) {
  // two triangles share positions 1 and 3 but with different normals on position 3
  const std::string path = writeFile("split.obj",
                                     "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                                     "vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n"
                                     "vn 0 0 1\nvn 0 1 0\n"
                                     "f 1/1/1 2/2/1 3/3/1\nf 2/2/1 4/4/1 3/3/2\n");
  Mesh m;
  ASSERT_TRUE(readObj(path, m).ok());
  ASSERT_EQ(m.vertexCount(), 5u);  // 4 positions + one more (3, vt 3, vn 2)
  ASSERT_EQ(m.normals.size(), 5u);
  ASSERT_EQ(m.uvs.size(), 5u);
  EXPECT_EQ(m.triangles, (std::vector<uint32_t>{0, 1, 2, 1, 3, 4}));
  EXPECT_EQ(m.positions[4], m.positions[2]);
  EXPECT_EQ(m.normals[2], glm::vec3(0, 0, 1));
  EXPECT_EQ(m.normals[4], glm::vec3(0, 1, 0));
  EXPECT_EQ(m.uvs[3], glm::vec2(1, 1));
}

TEST(ObjIo, ReadsLinesAsEdgesWithThicknessAndPoints) {
  const std::string path = writeFile("lines.obj",
                                     "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nv 5 5 5\n"
                                     "l 1 2 3\n#t 0.25\nl 3 4\np 5 1\n");
  Mesh m;
  ASSERT_TRUE(readObj(path, m).ok());
  EXPECT_EQ(m.edges, (std::vector<uint32_t>{0, 1, 1, 2, 2, 3}));
  EXPECT_EQ(m.edge_thickness, (std::vector<float>{0.0f, 0.0f, 0.25f}));
  EXPECT_EQ(m.points, (std::vector<uint32_t>{4, 0}));
  EXPECT_EQ(m.triangleCount(), 0u);
}

TEST(ObjIo, RoundTripIsExact) {
  Mesh m;
  m.positions = {{0.1f, 0.2f, 0.3f}, {1e-7f, -3.5e6f, 2.0f / 3.0f}, {1, 1, 0}, {0, 1, 0}, {7, 7, 7}};
  // vertex 4 is used only by an edge and a point: OBJ 'l' and 'p' carry no normal, so it has none
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0.6f, 0.8f}, {0, 0, 1}, {0, 0, 0}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}};
  m.face_offsets = {0, 4};
  m.face_corners = {0, 1, 2, 3};
  triangulateFaces(m);
  m.edges = {0, 4, 2, 4};
  m.edge_thickness = {0.0f, 0.125f};
  m.points = {4};
  const std::string path = test::scratchDir() + "/roundtrip.obj";
  ASSERT_TRUE(writeObj(path, m).ok());
  Mesh r;
  const Error e = readObj(path, r);
  ASSERT_TRUE(e.ok()) << e.message;
  EXPECT_EQ(r.positions, m.positions);
  EXPECT_EQ(r.normals, m.normals);
  EXPECT_EQ(r.uvs, m.uvs);
  EXPECT_EQ(r.face_offsets, m.face_offsets);
  EXPECT_EQ(r.face_corners, m.face_corners);
  EXPECT_EQ(r.triangles, m.triangles);
  EXPECT_EQ(r.edges, m.edges);
  EXPECT_EQ(r.edge_thickness, m.edge_thickness);
  EXPECT_EQ(r.points, m.points);
}

TEST(ObjIo, VertexColoursRoundTripThroughSrgb) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.colors = {{0.0f, 0.5f, 1.0f}, {0.2f, 0.001f, 0.9f}, {1, 1, 1}};
  m.triangles = {0, 1, 2};
  const std::string path = test::scratchDir() + "/colours.obj";
  ASSERT_TRUE(writeObj(path, m).ok());
  Mesh r;
  ASSERT_TRUE(readObj(path, r).ok());
  ASSERT_EQ(r.colors.size(), 3u);
  for (size_t i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.colors[i][k], m.colors[i][k], 1e-5f);
}

TEST(ObjIo, MissingFileNamesThePath) {
  Mesh m;
  const Error e = readObj("/nonexistent/dir/nothing.obj", m);
  EXPECT_EQ(e.status, Status::kIoError);
  EXPECT_TRUE(contains(e.message, "/nonexistent/dir/nothing.obj: cannot open file")) << e.message;
}

TEST(ObjIo, DirectoryIsNotAFile) {
  Mesh m;
  const Error e = readObj(test::scratchDir(), m);
  EXPECT_EQ(e.status, Status::kIoError);
  EXPECT_TRUE(contains(e.message, test::scratchDir() + ": cannot open file (not a regular file)")) << e.message;
}

TEST(ObjIo, IndexOutOfRangeNamesFileAndLine) {
  const std::string path = writeFile("oor.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n");
  Mesh m;
  const Error e = readObj(path, m);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_TRUE(contains(e.message, path + ":5: vertex index 9 out of range (the file has 3 vertices)")) << e.message;
}

TEST(ObjIo, RelativeIndexBeforeTheFirstVertexIsRefused) {
  const std::string path = writeFile("negoor.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n");
  Mesh m;
  const Error e = readObj(path, m);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_TRUE(contains(e.message, path + ":3: relative vertex index -3")) << e.message;
}

TEST(ObjIo, ZeroIndexIsRefused) {
  const std::string path = writeFile("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  Mesh m;
  const Error e = readObj(path, m);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_TRUE(contains(e.message, path + ":4: vertex index 0")) << e.message;
}

TEST(ObjIo, NanAndInfiniteCoordinatesAreRefused) {
  for (const char* bad : {"nan", "inf", "-inf", "1e999"}) {
    const std::string path = writeFile("nan.obj", std::string("v 0 0 0\nv 1 ") + bad + " 0\nv 0 1 0\nf 1 2 3\n");
    Mesh m;
    const Error e = readObj(path, m);
    EXPECT_EQ(e.status, Status::kInvalidMesh) << bad;
    EXPECT_TRUE(contains(e.message, path + ":2: NaN or infinite coordinate")) << e.message;
  }
}

TEST(ObjIo, MalformedNumbersAreRefused) {
  struct Case {
    const char* text;
    const char* message;
  };
  const Case cases[] = {
      {"v 0 0 0\nv 1 0x 0\n", ":2: malformed number '0x'"},
      {"v 0 0\n", ":1: 'v' statement needs at least 3 numbers, has 2"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 a\n", ":4: malformed vertex index 'a'"},
      {"v 0 0 0\nv 1 0 0\nf 1 2\n", ":3: face element needs at least 3 corners, has 2"},
      {"v 0 0 0\nvn 0 0 1\nvt 0 0\nf 1/1/1 1/1/1 1/1/x\n", ":4: malformed normal index 'x'"},
      {"v 0 0 0\n#t -1\nl 1 1\n", ":2: negative or non-finite thickness"},
  };
  for (const Case& c : cases) {
    const std::string path = writeFile("malformed.obj", c.text);
    Mesh m;
    const Error e = readObj(path, m);
    EXPECT_FALSE(e.ok()) << c.text;
    EXPECT_TRUE(contains(e.message, path + c.message)) << e.message;
  }
}

TEST(ObjIo, FilesThatAreNotObjAreRefused) {
  // an empty file, prose, and a GLB renamed .obj must not read as an empty mesh
  const std::string glb = std::string("glTF\x02\0\0\0", 8) + std::string("\x14\0\0\0JSON{}", 10);
  const struct {
    const char* name;
    std::string text;
    const char* expect;
  } cases[] = {
      {"empty.obj", "", "no vertices and no elements"},
      {"prose.obj", "Dear reader,\nthis is a letter, not a model.\n", "no vertices and no elements"},
      {"comments.obj", "# only a comment\no name\n", "no vertices and no elements"},
      {"renamed.obj", glb, "binary data"},
  };
  for (const auto& c : cases) {
    const std::string path = writeFile(c.name, c.text);
    Mesh m;
    const Error e = readObj(path, m);
    ASSERT_FALSE(e.ok()) << c.name;
    EXPECT_EQ(e.status, Status::kParseError) << c.name;
    EXPECT_TRUE(contains(e.message, path)) << e.message;
    EXPECT_TRUE(contains(e.message, c.expect)) << e.message;
  }
}

TEST(ObjIo, ReadsTheBunny) {
  SCENELOD_REQUIRE_BUNNY();
  Mesh m;
  const Error e = readObj(test::bunnyPath(), m);
  ASSERT_TRUE(e.ok()) << e.message;
  // glmark2's bunny: 34,835 'v' lines and 69,666 triangular 'f' lines, positions only
  EXPECT_EQ(m.vertexCount(), 34835u);
  EXPECT_EQ(m.triangleCount(), 69666u);
  EXPECT_EQ(m.faceCount(), 0u);
  EXPECT_TRUE(validateMesh(m, "bunny").ok());
}
