#include "scenelod/lodcore/mesh.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

using namespace scenelod;

namespace {
Mesh quad() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.triangles = {0, 1, 2, 0, 2, 3};
  return m;
}
}  // namespace

TEST(Mesh, ValidMeshPasses) { EXPECT_TRUE(validateMesh(quad(), "quad").ok()); }

TEST(Mesh, IndexOutOfRangeNamesTheTriangle) {
  Mesh m = quad();
  m.triangles[4] = 7;
  const Error e = validateMesh(m, "quad.obj");
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("quad.obj"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("triangle 1 uses vertex index 7"), std::string::npos) << e.message;
}

TEST(Mesh, NanCoordinateIsRefused) {
  Mesh m = quad();
  m.positions[2].y = std::numeric_limits<float>::quiet_NaN();
  const Error e = validateMesh(m, "quad.obj");
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("vertex 2 has a NaN or infinite coordinate"), std::string::npos) << e.message;
}

TEST(Mesh, MismatchedAttributeCountIsRefused) {
  Mesh m = quad();
  m.normals.resize(3);
  EXPECT_EQ(validateMesh(m, "q").status, Status::kInvalidMesh);
}

TEST(Mesh, ConcavePolygonTriangulatesInsideItsOutline) {
  // an L-shaped hexagon: a fan from corner 0 would cover area outside the polygon
  Mesh m;
  m.positions = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}, {1, 2, 0}, {0, 2, 0}};
  m.face_offsets = {0, 6};
  m.face_corners = {0, 1, 2, 3, 4, 5};
  // rotate the start so that the first corner is the reflex one
  m.face_corners = {3, 4, 5, 0, 1, 2};
  ASSERT_EQ(triangulateFaces(m), 4u);
  double area = 0.0;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const glm::vec3 a = m.positions[m.triangles[3 * t]], b = m.positions[m.triangles[3 * t + 1]],
                    c = m.positions[m.triangles[3 * t + 2]];
    const double z = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    EXPECT_GT(z, 0.0) << "triangle " << t << " is flipped or degenerate";
    area += 0.5 * z;
  }
  EXPECT_NEAR(area, 3.0, 1e-6);  // the L has area 3
}

TEST(Mesh, BoundsAndNormals) {
  Mesh m = quad();
  const Aabb b = computeBounds(m);
  EXPECT_FLOAT_EQ(b.diagonal(), std::sqrt(2.0f));
  computeVertexNormals(m);
  for (const glm::vec3& n : m.normals) EXPECT_NEAR(n.z, 1.0f, 1e-6f);
}
