// Geomorph targets of chain levels (LodLevel::morph), nested clustering chains and the rule that no
// level gains primitives.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>
#include <gtest/gtest.h>

#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/obj_io.h"
#include "scenelod/lodcore/zhang.h"
#include "test_hooks.h"
#include "test_support.h"

using namespace scenelod;

namespace {

Mesh testMesh() {
  Mesh m = test::makeSphere({0, 0, 0}, 1.0f, 48, 64);
  test::appendMesh(m, test::makeCadPart());
  return m;
}

// a grid with texture coordinates in two charts (left and right halves) and two triangle groups
Mesh texturedMesh() {
  Mesh m = test::makeBumpySphere(40, 60);
  m.uvs.resize(m.vertexCount());
  for (size_t v = 0; v < m.vertexCount(); ++v) {
    const glm::vec3 p = m.positions[v];
    m.uvs[v] = glm::vec2(std::atan2(p.y, p.x) * 0.15f + 0.5f, p.z * 0.5f + 0.5f);
  }
  m.triangle_groups.resize(m.triangleCount());
  for (size_t t = 0; t < m.triangleCount(); ++t) m.triangle_groups[t] = m.positions[m.triangles[3 * t]].z > 0.0f ? 1 : 0;
  return m;
}

using Key = std::array<float, 3>;
Key key(const glm::vec3& p) { return {p.x, p.y, p.z}; }

size_t primitives(const Mesh& m) { return m.triangleCount() + m.edgeCount() + m.pointCount(); }

void expectNoLevelGains(const LodChain& chain, const std::string& what) {
  for (size_t k = 1; k < chain.levelCount(); ++k) {
    const Mesh& a = chain.levels[k - 1].mesh;
    const Mesh& b = chain.levels[k].mesh;
    EXPECT_LE(b.triangleCount(), a.triangleCount()) << what << " level " << k;
    EXPECT_LE(primitives(b), primitives(a)) << what << " level " << k;
  }
}

// Level k drawn at morph factor 1 against level k + 1: its triangles that keep three distinct
// corners are level k + 1's triangles (as sets of corner positions), every edge and point of level
// k + 1 is the image of a level-k primitive, and every vertex lands on a vertex of level k + 1.
void expectExactMorphs(const LodChain& chain, const std::string& what) {
  for (size_t k = 0; k + 1 < chain.levelCount(); ++k) {
    const Mesh& a = chain.levels[k].mesh;
    const Mesh& b = chain.levels[k + 1].mesh;
    const LevelMorph& morph = chain.levels[k].morph;
    ASSERT_EQ(morph.positions.size(), a.vertexCount()) << what << " level " << k;
    std::set<Key> next_vertices;
    for (const glm::vec3& p : b.positions) next_vertices.insert(key(p));
    for (size_t u = 0; u < a.vertexCount(); ++u)
      ASSERT_TRUE(next_vertices.count(key(morph.positions[u]))) << what << " level " << k << " vertex " << u;
    auto sorted = [](std::vector<Key> c) {
      std::sort(c.begin(), c.end());
      return c;
    };
    std::set<std::vector<Key>> morphed, next, images;  // triangles; every primitive's image
    for (size_t t = 0; t < a.triangleCount(); ++t) {
      std::vector<Key> c;
      for (int i = 0; i < 3; ++i) c.push_back(key(morph.positions[a.triangles[3 * t + i]]));
      c = sorted(c);
      c.erase(std::unique(c.begin(), c.end()), c.end());
      if (c.size() == 3) morphed.insert(c);
      images.insert(c);
    }
    for (size_t e = 0; e < a.edgeCount(); ++e) {
      std::vector<Key> c = sorted({key(morph.positions[a.edges[2 * e]]), key(morph.positions[a.edges[2 * e + 1]])});
      c.erase(std::unique(c.begin(), c.end()), c.end());
      images.insert(c);
    }
    for (uint32_t p : a.points) images.insert({key(morph.positions[p])});
    for (size_t t = 0; t < b.triangleCount(); ++t)
      next.insert(sorted({key(b.positions[b.triangles[3 * t]]), key(b.positions[b.triangles[3 * t + 1]]),
                          key(b.positions[b.triangles[3 * t + 2]])}));
    EXPECT_EQ(morphed, next) << what << ": level " << k << " at factor 1 has " << morphed.size()
                             << " distinct triangles, level " << k + 1 << " " << next.size();
    for (size_t e = 0; e < b.edgeCount(); ++e)
      EXPECT_TRUE(images.count(sorted({key(b.positions[b.edges[2 * e]]), key(b.positions[b.edges[2 * e + 1]])})))
          << what << " level " << k + 1 << " edge " << e << " is no image of level " << k;
    for (uint32_t p : b.points)
      EXPECT_TRUE(images.count({key(b.positions[p])})) << what << " level " << k + 1 << " point is no image";
  }
  EXPECT_TRUE(chain.levels.back().morph.empty()) << what;
}

// per vertex: a third of its triangles' area
std::vector<double> vertexAreas(const Mesh& m) {
  std::vector<double> area(m.vertexCount(), 0.0);
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const uint32_t* i = &m.triangles[3 * t];
    const double a = glm::length(glm::cross(m.positions[i[1]] - m.positions[i[0]], m.positions[i[2]] - m.positions[i[0]])) / 6.0;
    for (int c = 0; c < 3; ++c) area[i[c]] += a;
  }
  return area;
}

bool sameGeometry(const Mesh& a, const Mesh& b) {
  return a.positions == b.positions && a.triangles == b.triangles && a.edges == b.edges && a.points == b.points;
}

}  // namespace

// Independent levels: every level-k vertex's target lies in the cell of the level-(k+1) cluster that
// holds most of the area of its level-k cluster's original vertices (the clusters recomputed here
// with assignClusters and clusterPrepared, apart from the chain).
TEST(Morph, IndependentTargetsLieInTheirNextClustersCell) {
  const Mesh m = testMesh();
  const std::vector<double> area = vertexAreas(m);
  for (LodMethod method : {LodMethod::kFloatingNearest, LodMethod::kFloatingHeaviest, LodMethod::kUniform}) {
    ChainParams cp;
    cp.cluster.method = method;
    cp.level_count = 6;
    cp.nested = false;
    LodChain chain;
    ASSERT_TRUE(buildChain(m, cp, chain).ok());
    PreparedMesh p;
    ASSERT_TRUE(prepareMesh(m, cp.cluster, p).ok());
    size_t checked_levels = 0, checked_vertices = 0;
    for (size_t k = 0; k + 1 < chain.levelCount(); ++k) {
      const LodLevel& level = chain.levels[k];
      ASSERT_EQ(level.morph.positions.size(), level.mesh.vertexCount());
      ASSERT_EQ(level.morph.normals.size(), chain.levels[k + 1].mesh.normals.empty() ? 0 : level.mesh.vertexCount());
      // this level's and the next level's clusters, as an independent clustering makes them
      ClusterParams at = cp.cluster;
      std::vector<std::vector<uint32_t>> sources(level.mesh.vertexCount());
      if (k == 0) {
        for (size_t u = 0; u < sources.size(); ++u) sources[u] = {uint32_t(u)};
      } else {
        at.cell_width = level.cell_width;
        Mesh again;
        ClusterOutputs outputs;
        ASSERT_TRUE(clusterPrepared(p, at, again, outputs).ok());
        if (!sameGeometry(again, level.mesh)) continue;  // a level rebuilt so as not to gain primitives
        ClusterAssignment a;
        ASSERT_TRUE(assignClusters(p, at, a).ok());
        std::vector<std::vector<uint32_t>> members(a.heaviest.size());
        for (size_t v = 0; v < a.cluster_of.size(); ++v)
          if (a.cluster_of[v] != UINT32_MAX) members[a.cluster_of[v]].push_back(uint32_t(v));
        for (size_t u = 0; u < sources.size(); ++u) sources[u] = members[a.cluster_of[outputs.source_vertex[u]]];
      }
      at.cell_width = chain.levels[k + 1].cell_width;
      {
        Mesh again;
        ASSERT_TRUE(clusterPrepared(p, at, again).ok());
        if (!sameGeometry(again, chain.levels[k + 1].mesh)) continue;
      }
      ClusterAssignment next;
      ASSERT_TRUE(assignClusters(p, at, next).ok());
      const float w = at.cell_width;
      for (size_t u = 0; u < sources.size(); ++u) {
        std::vector<double> sum(next.heaviest.size(), 0.0);
        double top = 0.0;
        for (uint32_t v : sources[u]) {
          const uint32_t c = next.cluster_of[v];
          if (c != UINT32_MAX) top = std::max(top, sum[c] += area[v] + 1e-12);
        }
        ASSERT_GT(top, 0.0);
        // the cell of a cluster with the largest share (those within rounding of it: symmetric parts tie)
        const glm::vec3 t = level.morph.positions[u];
        bool inside = false;
        for (uint32_t v : sources[u]) {
          const uint32_t c = next.cluster_of[v];
          if (c == UINT32_MAX || sum[c] < top * (1.0 - 1e-4)) continue;
          const glm::vec3 h = m.positions[next.heaviest[c]];
          glm::vec3 lo, hi;
          if (method == LodMethod::kUniform) {
            lo = p.bounds.min + glm::floor((h - p.bounds.min) / w) * w;
            hi = lo + glm::vec3(w);
          } else {
            lo = h - glm::vec3(0.5f * w);
            hi = h + glm::vec3(0.5f * w);
          }
          const glm::vec3 eps(1e-5f * w);
          inside = inside || (glm::all(glm::greaterThanEqual(t, lo - eps)) && glm::all(glm::lessThanEqual(t, hi + eps)));
        }
        ASSERT_TRUE(inside) << lodMethodName(method) << " level " << k << " vertex " << u << " target " << t.x << " " << t.y
                            << " " << t.z;
        ++checked_vertices;
      }
      ++checked_levels;
    }
    EXPECT_GE(checked_levels, chain.levelCount() - 2) << lodMethodName(method);
    EXPECT_GT(checked_vertices, m.vertexCount()) << lodMethodName(method);
  }
}

TEST(Morph, NestedLevelsAtFactorOneAreTheNextLevel) {
  for (LodMethod method : {LodMethod::kFloatingNearest, LodMethod::kFloatingHeaviest, LodMethod::kUniform}) {
    for (const Mesh& m : {testMesh(), texturedMesh()}) {
      ChainParams cp;
      cp.cluster.method = method;
      cp.level_count = 7;
      cp.nested = true;
      LodChain chain;
      ASSERT_TRUE(buildChain(m, cp, chain).ok());
      ASSERT_EQ(chain.levelCount(), 8u);
      const std::string what = std::string(lodMethodName(method)) + (m.uvs.empty() ? "" : " textured");
      expectExactMorphs(chain, what);
      expectNoLevelGains(chain, what);
      // (max_error may fall at the coarsest levels: one cluster's representative near the middle is
      // nearer to every vertex than two near the sides)
      for (size_t k = 1; k < chain.levelCount(); ++k) {
        EXPECT_GT(chain.levels[k].max_error, 0.0f) << what << " level " << k;
        if (!m.uvs.empty()) {
          EXPECT_EQ(chain.levels[k].source_vertex.size(), chain.levels[k].mesh.vertexCount());
          EXPECT_EQ(chain.levels[k - 1].morph.uvs.size(), chain.levels[k - 1].mesh.vertexCount());
        }
      }
    }
  }
}

TEST(Morph, ZhangLevelsAtFactorOneAreTheNextLevel) {
  for (const Mesh& m : {test::makeBumpySphere(40, 60), texturedMesh()}) {
    ChainParams cp;
    cp.cluster.method = LodMethod::kZhang;
    cp.level_count = 5;
    LodChain chain;
    ASSERT_TRUE(buildChain(m, cp, chain).ok());
    ASSERT_GE(chain.levelCount(), 4u);
    expectExactMorphs(chain, m.uvs.empty() ? "zhang" : "zhang textured");
    expectNoLevelGains(chain, "zhang");
  }
}

// the textured chain's targets take the attributes of a vertex of the next level at that position,
// in the vertex's own triangle group
TEST(Morph, TexturedTargetsTakeTheNextLevelsAttributes) {
  const Mesh m = texturedMesh();
  ChainParams cp;
  cp.level_count = 5;
  LodChain chain;
  ASSERT_TRUE(buildChain(m, cp, chain).ok());
  for (size_t k = 0; k + 1 < chain.levelCount(); ++k) {
    const Mesh& a = chain.levels[k].mesh;
    const Mesh& b = chain.levels[k + 1].mesh;
    const LevelMorph& morph = chain.levels[k].morph;
    ASSERT_EQ(morph.uvs.size(), a.vertexCount());
    ASSERT_EQ(morph.normals.size(), b.normals.empty() ? 0 : a.vertexCount());  // (level 0 has none: targets all the same)
    std::set<std::tuple<float, float, float, float, float>> next;
    for (size_t w = 0; w < b.vertexCount(); ++w)
      next.insert({b.positions[w].x, b.positions[w].y, b.positions[w].z, b.uvs[w].x, b.uvs[w].y});
    for (size_t u = 0; u < a.vertexCount(); ++u) {
      const glm::vec3 p = morph.positions[u];
      ASSERT_TRUE(next.count({p.x, p.y, p.z, morph.uvs[u].x, morph.uvs[u].y})) << "level " << k << " vertex " << u;
    }
  }
}

TEST(Morph, NoMorphsWhenNotAskedAndNoneOnTheLastLevel) {
  const Mesh m = testMesh();
  ChainParams cp;
  cp.level_count = 3;
  cp.morphs = false;
  LodChain chain;
  ASSERT_TRUE(buildChain(m, cp, chain).ok());
  for (const LodLevel& l : chain.levels) EXPECT_TRUE(l.morph.empty());
  cp.morphs = true;
  ASSERT_TRUE(buildChain(m, cp, chain).ok());
  for (size_t k = 0; k + 1 < chain.levelCount(); ++k) EXPECT_EQ(chain.levels[k].morph.positions.size(), chain.levels[k].mesh.vertexCount());
  EXPECT_TRUE(chain.levels.back().morph.empty());
  EXPECT_GT(chain.levels[0].morph.byteSize(), 0u);
}

// The chains of the CAD-like test part, with many levels (where independent floating-cell levels
// used to gain triangles at coarse widths), in every clustering mode
TEST(Morph, NoLevelGainsPrimitives) {
  const Mesh m = test::makeCadPart();
  for (LodMethod method : {LodMethod::kFloatingNearest, LodMethod::kFloatingHeaviest, LodMethod::kUniform}) {
    for (bool nested : {false, true}) {
      ChainParams cp;
      cp.cluster.method = method;
      cp.level_count = 12;
      cp.nested = nested;
      LodChain chain;
      ASSERT_TRUE(buildChain(m, cp, chain).ok());
      EXPECT_EQ(chain.levelCount(), 13u);
      expectNoLevelGains(chain, std::string(lodMethodName(method)) + (nested ? " nested" : ""));
    }
  }
}

TEST(Morph, BunnyNestedChainIsExact) {
  SCENELOD_REQUIRE_BUNNY();
  Mesh bunny;
  ASSERT_TRUE(readObj(test::bunnyPath(), bunny).ok());
  ChainParams cp;
  cp.nested = true;
  LodChain chain;
  ASSERT_TRUE(buildChain(bunny, cp, chain).ok());
  expectExactMorphs(chain, "bunny nested");
  expectNoLevelGains(chain, "bunny nested");
}

// A level rebuilt at the chain's end (so as not to gain primitives) after the geomorphs next to it
// were made gets them made again, from the maps of the levels next to it made again (their
// clustering repeated): forced here on levels 1, 3 and 4 (two in a row) of a plain and a textured
// (welded, two charts, two groups) mesh, with the shared models' two natural cases left to
// ChainMonotoneModels. Every pair with a rebuilt level has its targets, each a vertex of the next
// level (position and texture coordinates), most of them moved (a rebuilt level is not exactly the
// level before at factor 1, as a nested chain's levels are); every other pair is as in the chain
// without rebuilds. (That the maps made again are those the levels were built with, bit for bit,
// was checked against the chain that kept every level's maps until its end.)
TEST(Morph, RebuiltLevelsGetTheirGeomorphsAgain) {
  for (const Mesh& m : {testMesh(), texturedMesh()}) {
    const std::string what = m.uvs.empty() ? "plain" : "textured";
    ChainParams cp;
    cp.level_count = 6;
    LodChain plain, chain;
    ASSERT_TRUE(buildChain(m, cp, plain).ok());
    {
      detail::HookGuard rebuild(detail::setChainRebuildForTest, (1u << 1) | (1u << 3) | (1u << 4));
      ASSERT_TRUE(buildChain(m, cp, chain).ok());
    }
    ASSERT_EQ(chain.levelCount(), plain.levelCount());
    std::vector<bool> rebuilt(chain.levelCount());
    for (size_t k = 1; k < chain.levelCount(); ++k)
      rebuilt[k] = k == 1 || k == 3 || k == 4 || !sameGeometry(chain.levels[k].mesh, plain.levels[k].mesh);
    EXPECT_FALSE(sameGeometry(chain.levels[3].mesh, plain.levels[3].mesh)) << what << ": the rebuild changes level 3";
    for (size_t k = 0; k + 1 < chain.levelCount(); ++k) {
      const Mesh& a = chain.levels[k].mesh;
      const Mesh& b = chain.levels[k + 1].mesh;
      const LevelMorph& morph = chain.levels[k].morph;
      ASSERT_EQ(morph.positions.size(), a.vertexCount()) << what << " level " << k;
      ASSERT_EQ(morph.uvs.size(), m.uvs.empty() ? 0 : a.vertexCount()) << what << " level " << k;
      if (rebuilt[k] || rebuilt[k + 1]) {
        std::set<std::tuple<float, float, float, float, float>> next;
        for (size_t w = 0; w < b.vertexCount(); ++w)
          next.insert({b.positions[w].x, b.positions[w].y, b.positions[w].z, b.uvs.empty() ? 0.0f : b.uvs[w].x,
                       b.uvs.empty() ? 0.0f : b.uvs[w].y});
        size_t moved = 0;
        for (size_t u = 0; u < a.vertexCount(); ++u) {
          const glm::vec3 p = morph.positions[u];
          const glm::vec2 t = morph.uvs.empty() ? glm::vec2(0.0f) : morph.uvs[u];
          ASSERT_TRUE(next.count({p.x, p.y, p.z, t.x, t.y})) << what << " level " << k << " vertex " << u;
          moved += p != a.positions[u];
        }
        EXPECT_GT(moved, a.vertexCount() / 2) << what << " level " << k;
      } else {
        EXPECT_EQ(morph.positions, plain.levels[k].morph.positions) << what << " level " << k;
        EXPECT_EQ(morph.normals, plain.levels[k].morph.normals) << what << " level " << k;
        EXPECT_EQ(morph.uvs, plain.levels[k].morph.uvs) << what << " level " << k;
      }
    }
    EXPECT_TRUE(chain.levels.back().morph.empty()) << what;
  }
}

// With nested chains every triangle of level k that keeps three distinct corners at factor 1 is
// matched to a triangle of level k + 1 whose corners sit on its targets (morphCornerVertices), and
// every vertex's target (position, normal, texture coordinates) is that of a next-level vertex one
// of its triangles is drawn with there; most corners are drawn by their vertex's target itself
// (a vertex drawn by several is a crease of the next level through it).
TEST(Morph, NestedTargetsAreTheVerticesTheirTrianglesAreDrawnWith) {
  std::vector<std::pair<std::string, Mesh>> meshes = {{"plain", testMesh()}, {"textured", texturedMesh()}};
  Mesh bunny;
  if (readObj(test::bunnyPath(), bunny).ok()) meshes.push_back({"bunny", bunny});
  for (const auto& [what, m] : meshes) {
    ChainParams cp;
    cp.nested = true;
    cp.level_count = 6;
    LodChain chain;
    ASSERT_TRUE(buildChain(m, cp, chain).ok());
    size_t corners = 0, own_target = 0;
    for (size_t k = 0; k + 1 < chain.levelCount(); ++k) {
      const Mesh& a = chain.levels[k].mesh;
      const Mesh& b = chain.levels[k + 1].mesh;
      const LevelMorph& morph = chain.levels[k].morph;
      ASSERT_EQ(morph.normals.size(), b.normals.empty() ? 0 : a.vertexCount()) << what << " level " << k;
      std::vector<uint32_t> match;
      const std::vector<uint32_t> at = morphCornerVertices(chain.levels[k], b, &match);
      ASSERT_EQ(at.size(), a.triangles.size());
      ASSERT_EQ(match.size(), a.triangleCount());
      std::vector<uint8_t> drawn_by_target(a.vertexCount(), 0), has_corner(a.vertexCount(), 0);
      for (size_t t = 0; t < a.triangleCount(); ++t) {
        const uint32_t* u = &a.triangles[3 * t];
        const bool collapses = morph.positions[u[0]] == morph.positions[u[1]] ||
                               morph.positions[u[1]] == morph.positions[u[2]] ||
                               morph.positions[u[0]] == morph.positions[u[2]];
        ASSERT_EQ(at[3 * t] == UINT32_MAX, collapses) << what << " level " << k << " triangle " << t;
        ASSERT_EQ(match[t] == UINT32_MAX, collapses);
        if (collapses) continue;
        for (int i = 0; i < 3; ++i) {
          const uint32_t w = at[3 * t + i];
          ASSERT_LT(w, b.vertexCount());
          ASSERT_EQ(b.positions[w], morph.positions[u[i]]) << what << " level " << k;
          bool same = morph.normals.empty() || morph.normals[u[i]] == b.normals[w];
          same = same && (morph.uvs.empty() || morph.uvs[u[i]] == b.uvs[w]);
          has_corner[u[i]] = 1;
          drawn_by_target[u[i]] |= same;
          ++corners;
          own_target += same;
        }
      }
      for (size_t v = 0; v < a.vertexCount(); ++v)
        if (has_corner[v]) {
          ASSERT_TRUE(drawn_by_target[v]) << what << " level " << k << " vertex " << v;
        }
    }
    EXPECT_GT(corners, 0u) << what;
    EXPECT_GT(own_target, corners * 9 / 10) << what;
    std::printf("%s: %zu of %zu corners drawn by their vertex's own target\n", what.c_str(), own_target, corners);
  }
}

// morphCornerVertices on a level without morph targets, and on independent levels: no match is
// claimed where no next-level triangle lies on the targets
TEST(Morph, CornerVerticesOnlyWhereATriangleMatches) {
  const Mesh m = testMesh();
  ChainParams cp;
  cp.level_count = 4;
  cp.nested = false;
  LodChain chain;
  ASSERT_TRUE(buildChain(m, cp, chain).ok());
  LodLevel bare = chain.levels[1];
  bare.morph = LevelMorph();
  for (uint32_t w : morphCornerVertices(bare, chain.levels[2].mesh)) EXPECT_EQ(w, UINT32_MAX);
  for (size_t k = 0; k + 1 < chain.levelCount(); ++k) {
    const Mesh& a = chain.levels[k].mesh;
    const Mesh& b = chain.levels[k + 1].mesh;
    const std::vector<uint32_t> at = morphCornerVertices(chain.levels[k], b);
    for (size_t i = 0; i < at.size(); ++i)
      if (at[i] != UINT32_MAX) {
        ASSERT_EQ(b.positions[at[i]], chain.levels[k].morph.positions[a.triangles[i]]);
      }
  }
}
