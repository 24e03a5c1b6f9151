// countChangedTriangles: known answers on small meshes (Low & Tan 1997 §3.2.2's measure).
#include <algorithm>

#include <gtest/gtest.h>

#include "eval/test_meshes.h"
#include "scenelod/eval/consistency.h"

using namespace scenelod;

namespace {

Aabb everything() {
  Aabb box;
  box.min = glm::vec3(-100.0f);
  box.max = glm::vec3(100.0f);
  return box;
}

TEST(Consistency, IdenticalMeshesChangeNothing) {
  const Mesh m = test::makeIcosphere(2, 1.0f);
  const eval::TriangleChangeCount c = eval::countChangedTriangles(m, m, everything(), 0.0f);
  EXPECT_EQ(c.compared, m.triangleCount());
  EXPECT_EQ(c.changed, 0u);
}

TEST(Consistency, RotatedCornerOrderAndShuffledTrianglesAreTheSame) {
  const Mesh m = test::makeIcosphere(1, 1.0f);
  Mesh other = m;
  // rotate every triangle's corners by one and reverse the triangle order
  for (size_t t = 0; t < other.triangleCount(); ++t)
    std::rotate(other.triangles.begin() + long(3 * t), other.triangles.begin() + long(3 * t + 1),
                other.triangles.begin() + long(3 * t + 3));
  std::vector<uint32_t> reversed;
  for (size_t t = other.triangleCount(); t-- > 0;)
    reversed.insert(reversed.end(), other.triangles.begin() + long(3 * t), other.triangles.begin() + long(3 * t + 3));
  other.triangles = reversed;
  EXPECT_EQ(eval::countChangedTriangles(m, other, everything(), 0.0f).changed, 0u);
}

TEST(Consistency, FlippedOrMovedTrianglesCountAsChanged) {
  const Mesh m = test::makeIcosphere(1, 1.0f);  // 80 triangles
  Mesh flipped = m;
  std::swap(flipped.triangles[1], flipped.triangles[2]);  // triangle 0 flipped
  EXPECT_EQ(eval::countChangedTriangles(m, flipped, everything(), 0.0f).changed, 1u);

  // moving one vertex changes exactly the triangles around it (5 or 6 on an icosphere); a move
  // within eps changes none
  Mesh moved = m;
  const uint32_t v = m.triangles[0];
  const size_t around = size_t(std::count(m.triangles.begin(), m.triangles.end(), v));
  moved.positions[v] += glm::vec3(1e-3f, 0.0f, 0.0f);
  EXPECT_EQ(eval::countChangedTriangles(m, moved, everything(), 1e-4f).changed, around);
  EXPECT_EQ(eval::countChangedTriangles(m, moved, everything(), 2e-3f).changed, 0u);
}

TEST(Consistency, OnlyTrianglesInsideTheRegionAreCompared) {
  const Mesh a = test::makeIcosphere(1, 1.0f);
  Mesh both = a;
  const Mesh far = test::translated(test::makeIcosphere(1, 1.0f), glm::vec3(50.0f, 0.0f, 0.0f));
  const uint32_t base = uint32_t(both.positions.size());
  both.positions.insert(both.positions.end(), far.positions.begin(), far.positions.end());
  for (uint32_t i : far.triangles) both.triangles.push_back(base + i);
  Aabb region;
  region.min = glm::vec3(-1.5f);
  region.max = glm::vec3(1.5f);
  // every triangle of `both` near the origin matches one of `a`, the far copy is outside the region
  const eval::TriangleChangeCount c = eval::countChangedTriangles(both, a, region, 0.0f);
  EXPECT_EQ(c.compared, a.triangleCount());
  EXPECT_EQ(c.changed, 0u);
  // and against an empty mesh everything inside has changed
  EXPECT_EQ(eval::countChangedTriangles(a, Mesh{}, region, 0.0f).changed, a.triangleCount());
}

}  // namespace
