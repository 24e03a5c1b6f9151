#include "scenelod/scene/mesh_order.h"

#include <algorithm>
#include <array>
#include <random>

#include <gtest/gtest.h>

using namespace scenelod;
using namespace scenelod::scene;

namespace {

// an n x n grid of quads, triangles shuffled
Mesh shuffledGrid(uint32_t n, uint32_t seed) {
  Mesh m;
  for (uint32_t y = 0; y <= n; ++y)
    for (uint32_t x = 0; x <= n; ++x) m.positions.push_back({float(x), float(y), 0.0f});
  std::vector<std::array<uint32_t, 3>> tris;
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      const uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      tris.push_back({a, b, d});
      tris.push_back({a, d, c});
    }
  std::mt19937 rng(seed);
  std::shuffle(tris.begin(), tris.end(), rng);
  for (auto& t : tris) m.triangles.insert(m.triangles.end(), t.begin(), t.end());
  return m;
}

std::vector<std::array<uint32_t, 3>> triangleSet(const std::vector<uint32_t>& idx, const std::vector<glm::vec3>& pos) {
  // triangles as position-rounded corner triples so that vertex renumbering does not matter
  std::vector<std::array<uint32_t, 3>> out;
  for (size_t t = 0; t + 2 < idx.size(); t += 3) {
    std::array<uint32_t, 3> tri;
    for (int k = 0; k < 3; ++k) tri[k] = uint32_t(pos[idx[t + k]].x) * 1000 + uint32_t(pos[idx[t + k]].y);
    // keep the winding: rotate so the smallest comes first
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    out.push_back(tri);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST(MeshOrder, AcmrOfSmallCases) {
  const std::vector<uint32_t> one = {0, 1, 2}, two = {0, 1, 2, 2, 1, 3};
  EXPECT_DOUBLE_EQ(computeAcmr(Span<const uint32_t>(one.data(), one.size()), 3), 3.0);
  EXPECT_DOUBLE_EQ(computeAcmr(Span<const uint32_t>(two.data(), two.size()), 4), 2.0);
  // with a 3-entry fifo, vertex 0 is evicted by 3 and 4 before it is used again
  const std::vector<uint32_t> evict = {0, 1, 2, 3, 4, 1, 0, 3, 4};
  // fifo trace: 0 1 2 | 3 evicts 0 | 4 evicts 1 | 1 evicts 2 | 0 evicts 3 | 3 evicts 4 | 4 evicts 1: 9 misses
  EXPECT_DOUBLE_EQ(computeAcmr(Span<const uint32_t>(evict.data(), evict.size()), 5, 3), 9.0 / 3.0);
  EXPECT_DOUBLE_EQ(computeAcmr(Span<const uint32_t>(evict.data(), evict.size()), 5, 16), 5.0 / 3.0);
}

TEST(MeshOrder, VertexCacheKeepsTrianglesAndLowersAcmr) {
  const Mesh m = shuffledGrid(60, 1);
  std::vector<uint32_t> out(m.triangles.size());
  optimizeVertexCache(Span<uint32_t>(out.data(), out.size()), Span<const uint32_t>(m.triangles.data(), m.triangles.size()),
                      m.vertexCount());
  EXPECT_EQ(triangleSet(out, m.positions), triangleSet(m.triangles, m.positions));
  const double before = computeAcmr(Span<const uint32_t>(m.triangles.data(), m.triangles.size()), m.vertexCount());
  const double after = computeAcmr(Span<const uint32_t>(out.data(), out.size()), m.vertexCount());
  // a shuffled grid misses almost every corner; a cache-ordered grid approaches 0.5 (one new vertex
  // per two triangles) and stays well under 1
  EXPECT_GT(before, 2.5);
  EXPECT_LT(after, 1.0);
}

TEST(MeshOrder, MeshOrderRemapsEveryAttributeConsistently) {
  Mesh m = shuffledGrid(20, 2);
  const size_t n = m.vertexCount();
  for (size_t v = 0; v < n; ++v) {
    m.normals.push_back({0, 0, 1});
    m.colors.push_back({m.positions[v].x / 20.0f, m.positions[v].y / 20.0f, 0.5f});
  }
  m.positions.push_back({-5, -5, 0});  // unused vertex stays, at the end
  m.normals.push_back({1, 0, 0});
  m.colors.push_back({0, 0, 0});
  m.edges = {3, 7};
  m.edge_thickness = {0.5f};
  m.points = {9};
  const Mesh before = m;
  optimizeMeshOrder(m);
  ASSERT_EQ(m.vertexCount(), before.vertexCount());
  EXPECT_TRUE(validateMesh(m, "reordered").ok());
  EXPECT_EQ(triangleSet(m.triangles, m.positions), triangleSet(before.triangles, before.positions));
  for (size_t v = 0; v < m.vertexCount(); ++v)
    if (m.positions[v].x >= 0) {
      EXPECT_FLOAT_EQ(m.colors[v].x, m.positions[v].x / 20.0f);
    }
  EXPECT_EQ(m.positions.back(), glm::vec3(-5, -5, 0));
  EXPECT_EQ(m.positions[m.edges[0]], before.positions[3]);
  EXPECT_EQ(m.positions[m.edges[1]], before.positions[7]);
  EXPECT_EQ(m.positions[m.points[0]], before.positions[9]);
  // vertices are numbered in order of first use
  uint32_t next = 0;
  for (uint32_t i : m.triangles) {
    EXPECT_LE(i, next);
    if (i == next) ++next;
  }
}
