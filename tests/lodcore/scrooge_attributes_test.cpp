// SCROOGE on textured meshes: coplanar regions merge only inside one uv chart and one triangle group,
// moved points take interpolated uvs, groups are carried (docs/SCROOGE.md "Texture coordinates").
#include <cmath>
#include <set>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "scenelod/lodcore/scrooge.h"

using namespace scenelod;

namespace {

// a planar linear uv map, not aligned with the axes
glm::vec2 planeUv(const glm::vec3& p) { return {0.5f * p.x + 0.2f * p.y + 0.1f, -0.1f * p.x + 0.25f * p.y + 0.3f}; }

// n x n grid over [0, 1]^2 in z = 0 whose inner vertices are moved within the plane (so that edges
// bend and degradation moves points; the lines x = 0.5 and y = 0.5 stay straight), uv = planeUv;
// with `split`, the vertices on x = 0.5 are doubled and the right half's uvs shifted by (2, 0), a
// second chart
Mesh texturedPlane(int n, bool split) {
  Mesh m;
  auto index = [n](int i, int j) { return uint32_t(j * (n + 1) + i); };
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      glm::vec3 p(float(i) / float(n), float(j) / float(n), 0.0f);
      if (i > 0 && i < n && j > 0 && j < n && 2 * i != n && 2 * j != n) {
        p.x += 0.2f / float(n) * std::sin(float(7 * i + 3 * j));
        p.y += 0.2f / float(n) * std::cos(float(5 * i + 11 * j));
      }
      m.positions.push_back(p);
      m.uvs.push_back(planeUv(p));
      m.normals.push_back({0, 0, 1});
    }
  std::vector<uint32_t> twin(m.vertexCount(), 0);
  if (split)
    for (int j = 0; j <= n; ++j) {
      const uint32_t v = index(n / 2, j);
      twin[v] = uint32_t(m.positions.size());
      m.positions.push_back(m.positions[v]);
      m.uvs.push_back(m.uvs[v] + glm::vec2(2.0f, 0.0f));
      m.normals.push_back({0, 0, 1});
    }
  for (size_t v = 0; v < twin.size(); ++v)
    if (split && m.positions[v].x > 0.5f) m.uvs[v] += glm::vec2(2.0f, 0.0f);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      uint32_t c[4] = {index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)};
      if (split && 2 * i >= n)
        for (uint32_t& v : c)
          if (twin[v]) v = twin[v];
      m.triangles.insert(m.triangles.end(), {c[0], c[1], c[2], c[0], c[2], c[3]});
    }
  return m;
}

// every triangle's corners carry the uv of one chart's map at their position
void expectChartUvs(const Mesh& out, bool split) {
  ASSERT_EQ(out.uvs.size(), out.vertexCount());
  for (size_t t = 0; t < out.triangleCount(); ++t) {
    glm::vec3 centre(0.0f);
    for (int c = 0; c < 3; ++c) centre += out.positions[out.triangles[3 * t + c]] / 3.0f;
    const glm::vec2 shift = split && centre.x > 0.5f ? glm::vec2(2.0f, 0.0f) : glm::vec2(0.0f);
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = out.triangles[3 * t + c];
      const glm::vec2 want = planeUv(out.positions[v]) + shift;
      EXPECT_NEAR(out.uvs[v].x, want.x, 2e-6f) << "triangle " << t << " corner " << c;
      EXPECT_NEAR(out.uvs[v].y, want.y, 2e-6f) << "triangle " << t << " corner " << c;
    }
  }
}

TEST(ScroogeAttributes, OneChartPlaneKeepsItsUvsWherePointsMove) {
  const Mesh plane = texturedPlane(12, false);
  for (int divisions : {1, 2, 4}) {
    SCOPED_TRACE(divisions);
    ScroogeParams params;
    params.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(plane), divisions);
    Mesh out;
    ScroogeStats stats;
    ASSERT_TRUE(scroogeMesh(plane, params, out, &stats).ok());
    EXPECT_GT(stats.moved_vertices, 0u);
    EXPECT_LT(out.triangleCount(), plane.triangleCount());
    expectChartUvs(out, false);
    ASSERT_EQ(stats.source_vertex.size(), out.vertexCount());
    for (uint32_t src : stats.source_vertex) ASSERT_LT(src, plane.vertexCount());
  }
}

TEST(ScroogeAttributes, CoplanarRegionIsSplitAtItsChartBorder) {
  const Mesh plane = texturedPlane(12, true);
  ScroogeParams params;
  params.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(plane), 1);
  Mesh out;
  ASSERT_TRUE(scroogeMesh(plane, params, out).ok());
  EXPECT_LT(out.triangleCount(), plane.triangleCount() / 4);
  expectChartUvs(out, true);
  // the border's points never move: every output vertex at x = 0.5 is an input vertex there
  size_t on_border = 0;
  for (const glm::vec3& p : out.positions) on_border += std::fabs(p.x - 0.5f) < 1e-6f;
  EXPECT_GE(on_border, 4u);
}

TEST(ScroogeAttributes, TriangleGroupsAreCarriedAndNeverMerged) {
  Mesh plane = texturedPlane(12, false);
  for (size_t t = 0; t < plane.triangleCount(); ++t) {
    glm::vec3 centre(0.0f);
    for (int c = 0; c < 3; ++c) centre += plane.positions[plane.triangles[3 * t + c]] / 3.0f;
    plane.triangle_groups.push_back(centre.y < 0.5f ? 4u : 7u);
  }
  ScroogeParams params;
  params.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(plane), 1);
  Mesh out;
  ASSERT_TRUE(scroogeMesh(plane, params, out).ok());
  ASSERT_EQ(out.triangle_groups.size(), out.triangleCount());
  EXPECT_EQ(std::set<uint32_t>(out.triangle_groups.begin(), out.triangle_groups.end()), (std::set<uint32_t>{4, 7}));
  for (size_t t = 0; t < out.triangleCount(); ++t)
    for (int c = 0; c < 3; ++c) {
      const float y = out.positions[out.triangles[3 * t + c]].y;
      if (out.triangle_groups[t] == 4u) EXPECT_LE(y, 0.5f + 1e-6f) << "triangle " << t;
      else EXPECT_GE(y, 0.5f - 1e-6f) << "triangle " << t;
    }
  expectChartUvs(out, false);
}

TEST(ScroogeAttributes, PolygonFacesTakeTheirTrianglesGroups) {
  // two quads as faces over their triangulation, in groups 1 and 2: coplanar, yet never merged
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 1, 0}};
  m.face_offsets = {0, 4, 8};
  m.face_corners = {0, 1, 4, 3, 1, 2, 5, 4};
  m.triangles = {0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4};
  m.triangle_groups = {1, 1, 2, 2};
  ScroogeParams params;
  params.subvolume_size = glm::vec3(4.0f);
  Mesh out;
  ScroogeStats stats;
  ASSERT_TRUE(scroogeMesh(m, params, out, &stats).ok());
  EXPECT_EQ(stats.merged_groups, 0u);
  ASSERT_EQ(out.triangle_groups.size(), out.triangleCount());
  for (size_t t = 0; t < out.triangleCount(); ++t) {
    float x = 0.0f;
    for (int c = 0; c < 3; ++c) x += out.positions[out.triangles[3 * t + c]].x / 3.0f;
    EXPECT_EQ(out.triangle_groups[t], x < 1.0f ? 1u : 2u);
  }
  // without groups the two quads merge into one polygon
  m.triangle_groups.clear();
  ASSERT_TRUE(scroogeMesh(m, params, out, &stats).ok());
  EXPECT_EQ(stats.merged_groups, 1u);
  EXPECT_TRUE(out.triangle_groups.empty());
}

TEST(ScroogeAttributes, ChainLevelsRecordTheirSourceVertices) {
  const Mesh plane = texturedPlane(12, true);
  ChainParams params;
  params.level_count = 3;
  LodChain chain;
  ASSERT_TRUE(buildScroogeChain(plane, params, chain).ok());
  ASSERT_EQ(chain.levelCount(), 4u);
  for (size_t l = 1; l < chain.levelCount(); ++l) {
    const LodLevel& level = chain.levels[l];
    ASSERT_EQ(level.source_vertex.size(), level.mesh.vertexCount()) << "level " << l;
    // an output vertex that did not move is its source vertex
    for (size_t v = 0; v < level.mesh.vertexCount(); ++v)
      if (level.mesh.positions[v] == plane.positions[level.source_vertex[v]])
        EXPECT_EQ(level.mesh.uvs[v], plane.uvs[level.source_vertex[v]]) << "level " << l << " vertex " << v;
    expectChartUvs(level.mesh, true);
  }
}

}  // namespace
