// Elimination (Low & Tan 1997 §2 step 5) and thick edges (§3.3.1) on constructed meshes.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/obj_io.h"
#include "scenelod/lodcore/thick_edge.h"
#include "test_hooks.h"
#include "test_support.h"

using namespace scenelod;

namespace {

ClusterParams floating(float w) {
  ClusterParams p;
  p.method = LodMethod::kFloatingNearest;
  p.cell_width = w;
  return p;
}

Mesh run(const Mesh& m, const ClusterParams& p) {
  Mesh out;
  const Error e = clusterMesh(m, p, out);
  EXPECT_TRUE(e.ok()) << e.message;
  return out;
}

}  // namespace

TEST(Elimination, ThreeOneAndTwoClusterTrianglesBecomeTriangleEdgeAndPoint) {
  Mesh m;
  m.positions = {{0, 0, 0}, {3, 0, 0}, {0, 3, 0},               // big: 3 clusters
                 {10, 0, 0}, {10.01f, 0, 0}, {10, 4, 0},        // thin: 2 clusters
                 {20, 0, 0}, {20.01f, 0, 0}, {20, 0.01f, 0}};   // tiny: 1 cluster
  m.triangles = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  const Mesh out = run(m, floating(0.2f));
  EXPECT_EQ(out.triangleCount(), 1u);
  EXPECT_EQ(out.edgeCount(), 1u);
  EXPECT_EQ(out.pointCount(), 1u);
  EXPECT_NEAR(out.positions[out.points[0]].x, 20.0f, 0.02f);
}

TEST(Elimination, DuplicateTrianglesOfTheSameOrientationMerge) {
  Mesh m;
  m.positions = {{0, 0, 0}, {3, 0, 0}, {0, 3, 0}, {0.01f, 0, 0}, {3.01f, 0, 0}, {0.01f, 3, 0}};
  m.triangles = {0, 1, 2, 4, 5, 3};  // the second is a rotation of a near-copy
  const Mesh out = run(m, floating(0.2f));
  EXPECT_EQ(out.triangleCount(), 1u);
  EXPECT_EQ(out.edgeCount(), 0u);
  EXPECT_EQ(out.pointCount(), 0u);
}

TEST(Elimination, OppositeOrientationsStayAsATwoSidedSheet) {
  Mesh m;
  m.positions = {{0, 0, 0}, {3, 0, 0}, {0, 3, 0}, {0.01f, 0, 0}, {3.01f, 0, 0}, {0.01f, 3, 0}};
  m.triangles = {0, 1, 2, 3, 5, 4};  // reversed winding
  const Mesh out = run(m, floating(0.2f));
  ASSERT_EQ(out.triangleCount(), 2u);
  // same corners (as positions), opposite normals
  const glm::vec3 n0 = glm::cross(out.positions[out.triangles[1]] - out.positions[out.triangles[0]],
                                  out.positions[out.triangles[2]] - out.positions[out.triangles[0]]);
  const glm::vec3 n1 = glm::cross(out.positions[out.triangles[4]] - out.positions[out.triangles[3]],
                                  out.positions[out.triangles[5]] - out.positions[out.triangles[3]]);
  EXPECT_LT(glm::dot(glm::normalize(n0), glm::normalize(n1)), -0.999f);
}

TEST(Elimination, EdgesCoveredByTrianglesAndPointsCoveredByEdgesAreRemoved) {
  Mesh m;
  m.positions = {{0, 0, 0}, {3, 0, 0}, {0, 3, 0},      // a triangle
                 {3.01f, 0.01f, 0},                     // sliver (0, 1, 3) collapses onto its edge 0-1
                 {0.01f, 0.01f, 0}, {0.0f, 0.02f, 0},   // tiny triangle (0, 4, 5) collapses onto vertex 0
                 {10, 0, 0}, {13, 0, 0}, {10.01f, 0, 0}, {13.01f, 0.01f, 0}};  // two slivers on one edge
  m.triangles = {0, 1, 2, 0, 3, 1, 0, 4, 5, 6, 7, 9, 6, 8, 7};
  const Mesh out = run(m, floating(0.2f));
  EXPECT_EQ(out.triangleCount(), 1u);
  EXPECT_EQ(out.edgeCount(), 1u);   // 10-13 once; 0-3 is covered by the triangle
  EXPECT_EQ(out.pointCount(), 0u);  // vertex 0 is covered by the triangle
}

TEST(Elimination, AClusterWithManyCollapsedEdgesKeepsEachOnce) {
  // 20 spokes from one hub, each made of two slivers that collapse onto the same edge: the hub's
  // cluster heads more candidate edges than are kept inline per cluster
  Mesh m;
  m.positions = {{0, 0, 0}, {0.01f, 0, 0}};
  const int spokes = 20;
  for (int i = 0; i < spokes; ++i) {
    const float a = 6.2831853f * float(i) / float(spokes);
    const glm::vec3 tip(10.0f * std::cos(a), 10.0f * std::sin(a), 0.0f);
    const uint32_t v = static_cast<uint32_t>(m.positions.size());
    m.positions.insert(m.positions.end(), {tip, tip + glm::vec3(0, 0, 0.01f), tip + glm::vec3(0, 0, 0.02f)});
    m.triangles.insert(m.triangles.end(), {0, v, v + 1, 1, v + 2, v});
  }
  const Mesh out = run(m, floating(0.2f));
  EXPECT_EQ(out.triangleCount(), 0u);
  ASSERT_EQ(out.edgeCount(), size_t(spokes));
  EXPECT_EQ(out.pointCount(), 0u);
  std::vector<float> angles;
  for (size_t e = 0; e < out.edgeCount(); ++e) {
    glm::vec3 a = out.positions[out.edges[2 * e]], b = out.positions[out.edges[2 * e + 1]];
    if (glm::length(a) > glm::length(b)) std::swap(a, b);
    EXPECT_LT(glm::length(a), 0.1f);  // one end at the hub
    EXPECT_NEAR(glm::length(b), 10.0f, 0.1f);
    angles.push_back(std::atan2(b.y, b.x));
  }
  std::sort(angles.begin(), angles.end());
  for (size_t k = 1; k < angles.size(); ++k) EXPECT_GT(angles[k] - angles[k - 1], 0.2f);  // all spokes distinct
}

TEST(Elimination, MoreCandidateEdgesThanSixteenBitsOnFewClusters) {
  // 400 clusters (one per vertex) and 72,100 input edges, each listed twice in opposite directions:
  // first every pair of clusters 0-379 (71,910), then every pair of 380-399, whose blocks (used
  // below 2^15 clusters, with 16-bit ids) are still empty when their edge ids have passed 16 bits,
  // so they are chained instead; each pair must come out once, with the larger of its two input
  // thicknesses (an id cut to 16 bits would find another edge, an id chained but not looked for
  // would list the pair twice)
  Mesh m;
  const int side = 20, n = side * side, split = 380;
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) m.positions.push_back({float(x), float(y), 0.0f});
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < split; ++i)
    for (int j = i + 1; j < split; ++j) pairs.push_back({i, j});
  for (int i = split; i < n; ++i)
    for (int j = i + 1; j < n; ++j) pairs.push_back({i, j});
  ASSERT_GT(pairs.size(), size_t(65535));
  auto forward = [](int i) { return 0.001f * float(i % 7); };
  auto backward = [](int j) { return 0.001f * float(j % 5); };
  for (const auto& [i, j] : pairs) {
    m.edges.insert(m.edges.end(), {uint32_t(i), uint32_t(j)});
    m.edge_thickness.push_back(forward(i));
  }
  for (const auto& [i, j] : pairs) {
    m.edges.insert(m.edges.end(), {uint32_t(j), uint32_t(i)});
    m.edge_thickness.push_back(backward(j));
  }
  const Mesh out = run(m, floating(0.2f));
  ASSERT_EQ(out.edgeCount(), pairs.size());
  ASSERT_EQ(out.edge_thickness.size(), pairs.size());
  EXPECT_EQ(out.pointCount(), 0u);
  std::vector<uint8_t> seen(size_t(n) * size_t(n), 0);
  size_t wrong_thickness = 0, repeated = 0;
  for (size_t e = 0; e < out.edgeCount(); ++e) {
    const glm::vec3 a = out.positions[out.edges[2 * e]], b = out.positions[out.edges[2 * e + 1]];
    int i = int(std::lround(a.y)) * side + int(std::lround(a.x));
    int j = int(std::lround(b.y)) * side + int(std::lround(b.x));
    if (i > j) std::swap(i, j);
    ASSERT_LT(i, j);
    ASSERT_EQ(i < split, j < split);
    repeated += seen[size_t(i) * size_t(n) + size_t(j)]++ != 0;
    wrong_thickness += out.edge_thickness[e] != std::max(forward(i), backward(j));
  }
  EXPECT_EQ(repeated, 0u);
  EXPECT_EQ(wrong_thickness, 0u);
}

TEST(Elimination, InputEdgesAndPointsAreClusteredToo) {
  Mesh m;
  m.positions = {{0, 0, 0}, {5, 0, 0}, {0.01f, 0, 0}, {9, 9, 9}, {9.01f, 9, 9}};
  m.edges = {0, 1, 0, 2, 3, 4};
  m.edge_thickness = {0.3f, 0.0f, 0.0f};
  m.points = {2};
  const Mesh out = run(m, floating(0.2f));
  EXPECT_EQ(out.edgeCount(), 1u);   // 0-1 stays, 0-2 collapses to a point covered by it
  EXPECT_EQ(out.pointCount(), 1u);  // 3-4 collapses to a point
  ASSERT_EQ(out.edge_thickness.size(), 1u);
  EXPECT_FLOAT_EQ(out.edge_thickness[0], 0.3f);  // input thickness kept
}

TEST(ThickEdge, ThinCylinderCollapsesToEdgesAsThickAsItsDiameter) {
  const float r = 0.05f;
  const Mesh cyl = test::makeCylinder(0.0f, 6.0f, r, 24, 16);
  const Mesh out = run(cyl, floating(0.6f));
  EXPECT_EQ(out.triangleCount(), 0u);
  ASSERT_GT(out.edgeCount(), 3u);
  ASSERT_EQ(out.edge_thickness.size(), out.edgeCount());
  // V_A is a full ring around the axis: P_A is on the axis and D_A = r, so thickness = 2r
  for (float t : out.edge_thickness) EXPECT_NEAR(t, 2.0f * r, 2e-3f);
}

TEST(ThickEdge, ThicknessIsTheSameWhenMoreTrianglesCollapseThanAreListed) {
  // Beside a fine closed box, far more triangles collapse onto (covered) edges than the elimination
  // lists, so it finds the triangles of the edges left uncovered (the cylinder's) by classifying
  // their blocks again; the thickness must be that of the cylinder alone, whose few are listed.
  const Mesh cyl = test::makeCylinder(0.0f, 6.0f, 0.05f, 24, 16);
  const Mesh alone = run(cyl, floating(0.6f));
  std::vector<float> expected(alone.edge_thickness);
  std::sort(expected.begin(), expected.end());
  ASSERT_GT(expected.size(), 3u);
  for (bool box_first : {true, false}) {
    Mesh m;
    const Mesh box = test::makeBox({20, 20, 20}, {28, 28, 28}, 60);  // 43 200 triangles, spacing 0.13
    if (box_first) test::appendMesh(m, box);
    test::appendMesh(m, cyl);
    if (!box_first) test::appendMesh(m, box);
    const Mesh out = run(m, floating(0.6f));
    std::vector<float> got;
    for (size_t e = 0; e < out.edgeCount(); ++e)
      if (out.positions[out.edges[2 * e]].y < 10.0f) got.push_back(out.edge_thickness[e]);  // the cylinder's
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got.size(), expected.size()) << "box first " << box_first;
    for (size_t k = 0; k < got.size(); ++k) EXPECT_EQ(got[k], expected[k]) << "box first " << box_first;
  }
}

TEST(ThickEdge, ThinBoxThicknessLiesBetweenItsWidthAndDiagonal) {
  const float s = 0.1f;
  const Mesh box = test::makeBox({0, 0, 0}, {4.0f, s, s}, 8);
  const Mesh out = run(box, floating(0.6f));
  ASSERT_GT(out.edgeCount(), 2u);
  for (float t : out.edge_thickness) {
    // cross-section vertices lie between s/2 (side middles) and s/sqrt(2) (corners) from the axis
    EXPECT_GE(t, s - 1e-4f);
    EXPECT_LE(t, s * std::sqrt(2.0f) + 1e-4f);
  }
}

TEST(ThickEdge, DynamicNormalIsPerpendicularAndFacesTheCamera) {
  const glm::vec3 v1(0, 0, 0), v2(2, 0.5f, 0), cam(1, 3, 4);
  const glm::vec3 n = dynamicNormal(v1, v2, cam);
  EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
  EXPECT_NEAR(glm::dot(n, v2 - v1), 0.0f, 1e-5f);                        // perpendicular to the edge
  EXPECT_NEAR(glm::dot(n, glm::cross(v1 - cam, v2 - cam)), 0.0f, 1e-4f);  // in the edge-camera plane
  EXPECT_GT(glm::dot(n, cam - v1), 0.0f);                                 // acute angle to the camera
  EXPECT_GT(glm::dot(n, cam - v2), 0.0f);
  EXPECT_EQ(dynamicNormal(v1, v2, 0.5f * v2), glm::vec3(0.0f));           // camera on the edge's line
  EXPECT_FLOAT_EQ(thickEdgePixelWidth(0.5f, 0.1f), 5.0f);
  EXPECT_FLOAT_EQ(thickEdgePixelWidth(0.01f, 0.1f), 1.0f);
}

namespace {

using test::sameBits;

// the mesh with its vertex ids and its triangles in a scrambled order (a fixed LCG), so that
// neighbouring triangles no longer share cache lines of the cluster ids
Mesh scrambled(const Mesh& in) {
  const size_t n = in.positions.size(), t = in.triangleCount();
  uint64_t state = 12345;
  auto next = [&](size_t bound) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return size_t(state >> 33) % bound;
  };
  std::vector<uint32_t> to(n), order(t);
  for (size_t i = 0; i < n; ++i) to[i] = uint32_t(i);
  for (size_t i = n; i > 1; --i) std::swap(to[i - 1], to[next(i)]);
  for (size_t i = 0; i < t; ++i) order[i] = uint32_t(i);
  for (size_t i = t; i > 1; --i) std::swap(order[i - 1], order[next(i)]);
  Mesh m;
  m.positions.resize(n);
  for (size_t i = 0; i < n; ++i) m.positions[to[i]] = in.positions[i];
  for (size_t i = 0; i < t; ++i)
    for (int k = 0; k < 3; ++k) m.triangles.push_back(to[in.triangles[3 * order[i] + k]]);
  return m;
}

// the diagonal of the box of every position
float positionsDiagonal(const Mesh& m) {
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (const glm::vec3& q : m.positions) {
    lo = glm::min(lo, q);
    hi = glm::max(hi, q);
  }
  return glm::length(hi - lo);
}

// every array of two clusterings bit for bit
void expectSameBits(const Mesh& a, const Mesh& b) {
  EXPECT_TRUE(sameBits(a.positions, b.positions));
  EXPECT_TRUE(sameBits(a.normals, b.normals));
  EXPECT_TRUE(sameBits(a.triangles, b.triangles));
  EXPECT_TRUE(sameBits(a.edges, b.edges));
  EXPECT_TRUE(sameBits(a.edge_thickness, b.edge_thickness));
  EXPECT_TRUE(sameBits(a.points, b.points));
}

// the bunny (where installed) and thin cylinders beside a box (uncovered edges: thickness), the
// first meshes of the tests comparing two elimination paths
void addBunnyAndSheet(std::vector<std::pair<std::string, Mesh>>& meshes) {
  if (test::fileExists(test::bunnyPath())) {
    Mesh bunny;
    ASSERT_TRUE(readObj(test::bunnyPath(), bunny).ok());
    meshes.emplace_back("bunny", std::move(bunny));
  }
  Mesh sheet;
  test::appendMesh(sheet, test::makeBox({20, 20, 20}, {28, 28, 28}, 30));
  for (int k = 0; k < 5; ++k)
    test::appendMesh(sheet, test::makeCylinder(0.0f, 6.0f, 0.05f, 24, 16 + k, glm::vec3(0.0f, 0.5f * k, 0.0f)));
  meshes.emplace_back("box and cylinders", std::move(sheet));
}

}  // namespace

// The AVX2 classification (eight triangles at once, where the CPU has AVX2) gives the baseline's
// bits: every output array, at fine and coarse widths (kept triangles, edges or points dominating),
// with edges or points not kept, on the bunny (69,666 triangles: a block tail not a multiple of 8),
// thin cylinders beside a box (uncovered edges: thickness), and a scrambled sphere over 2^18
// vertices (the prefetching variant). On a CPU without AVX2 both runs take the baseline.
TEST(Elimination, Avx2ClassificationGivesTheBaselineBits) {
  std::vector<std::pair<std::string, Mesh>> meshes;
  addBunnyAndSheet(meshes);
  ASSERT_FALSE(HasFatalFailure());
  meshes.emplace_back("bumpy sphere", test::makeBumpySphere(90, 121));
  meshes.emplace_back("scrambled sphere", scrambled(test::makeBumpySphere(400, 700)));
  ASSERT_GT(meshes.back().second.positions.size(), size_t(1) << 18);
  detail::HookGuard avx2(detail::useAvx2Paths, true);
  size_t levels = 0;
  for (const auto& [name, m] : meshes) {
    const float diagonal = positionsDiagonal(m);
    for (float f : {0.004f, 0.015f, 0.05f, 0.15f})
      for (int keep = 0; keep < 3; ++keep) {
        if (m.positions.size() > (size_t(1) << 18) && keep != 0) continue;  // (the test's time)
        ClusterParams p;
        p.cell_width = f * diagonal;
        p.keep_edges = keep != 1;
        p.keep_points = keep != 2;
        Mesh wide, base;
        avx2.set(true);
        ASSERT_TRUE(clusterMesh(m, p, wide).ok());
        avx2.set(false);
        ASSERT_TRUE(clusterMesh(m, p, base).ok());
        SCOPED_TRACE(name + " w=" + std::to_string(p.cell_width) + " keep " + std::to_string(keep));
        ASSERT_GT(base.triangleCount(), 0u);
        expectSameBits(wide, base);
        ++levels;
      }
  }
  EXPECT_GE(levels, 28u);
}

namespace {

// a bumpy sphere with input edges across its surface (input thicknesses), 40 hubs of 24 spokes and
// a finer bumpy sphere (edge lists longer than three nodes)
void addEdgeMeshes(std::vector<std::pair<std::string, Mesh>>& meshes) {
  Mesh sphere = test::makeBumpySphere(90, 121);
  for (uint32_t v = 0; v + 7 < sphere.positions.size(); v += 7) {  // input edges across the surface
    sphere.edges.insert(sphere.edges.end(), {v, v + 7});
    sphere.edge_thickness.push_back(0.001f * float(v % 13));
  }
  meshes.emplace_back("bumpy sphere with edges", std::move(sphere));
  Mesh hubs;  // 40 hubs of 24 spokes, each spoke two slivers collapsing onto one edge
  for (int h = 0; h < 40; ++h) {
    const glm::vec3 c(30.0f * float(h % 8), 30.0f * float(h / 8), 0.0f);
    const uint32_t hub = static_cast<uint32_t>(hubs.positions.size());
    hubs.positions.insert(hubs.positions.end(), {c, c + glm::vec3(0.01f, 0, 0)});
    for (int i = 0; i < 24; ++i) {
      const float a = 6.2831853f * float(i) / 24.0f;
      const glm::vec3 tip = c + glm::vec3(10.0f * std::cos(a), 10.0f * std::sin(a), 0.0f);
      const uint32_t v = static_cast<uint32_t>(hubs.positions.size());
      hubs.positions.insert(hubs.positions.end(), {tip, tip + glm::vec3(0, 0, 0.01f), tip + glm::vec3(0, 0, 0.02f)});
      hubs.triangles.insert(hubs.triangles.end(), {hub, v, v + 1, hub + 1, v + 2, v});
    }
  }
  meshes.emplace_back("hubs", std::move(hubs));
  meshes.emplace_back("finer bumpy sphere", test::makeBumpySphere(300, 400));
}

}  // namespace

// Dropping the collapsed triangles whose cluster pair or point repeats the one before (in lanes
// and scalar) gives the bits of looking every one up: every output array, with edges or points not kept, at
// fine and coarse widths, on the meshes above (the generator's ring order, where about half the
// pairs repeat; the hubs, whose pairs alternate in direction), the scrambled sphere (few repeats,
// the prefetching classification), with the AVX2 paths and without.
TEST(Elimination, DroppedRepeatedEdgesGiveTheReferenceBits) {
  std::vector<std::pair<std::string, Mesh>> meshes;
  addBunnyAndSheet(meshes);
  ASSERT_FALSE(HasFatalFailure());
  addEdgeMeshes(meshes);
  // 48 thin cylinders, half of them along x and half along y, crossing (over 4,096 collapsed
  // triangles, so that their list is dropped, and most edges uncovered: output edges)
  Mesh hair;
  for (int k = 0; k < 48; ++k) {
    Mesh c = test::makeCylinder(0.0f, 6.0f, 0.02f, 40, 12, glm::vec3(0.0f, 0.37f * float(k % 12), 0.23f * float(k / 24)));
    if (k % 2)
      for (glm::vec3& q : c.positions) q = glm::vec3(q.y, q.x, q.z + 0.01f);
    test::appendMesh(hair, c);
  }
  meshes.emplace_back("hair", std::move(hair));
  meshes.emplace_back("scrambled sphere", scrambled(test::makeBumpySphere(400, 700)));
  detail::HookGuard drop(detail::useRepeatedEdgeDrop, true);
  detail::HookGuard avx2_paths(detail::useAvx2Paths, true);
  size_t levels = 0;
  for (const auto& [name, m] : meshes) {
    const float diagonal = positionsDiagonal(m);
    const bool large = m.positions.size() > (size_t(1) << 18);
    for (float f : {0.002f, 0.004f, 0.015f, 0.05f, 0.15f})
      for (int keep = 0; keep < 3; ++keep) {
        if (large && (keep != 0 || f < 0.004f)) continue;  // (the test's time)
        ClusterParams p;
        p.cell_width = f * diagonal;
        p.keep_edges = keep != 1;
        p.keep_points = keep != 2;
        Mesh reference;
        drop.set(false);
        ASSERT_TRUE(clusterMesh(m, p, reference).ok());
        drop.set(true);
        for (bool avx2 : {true, false}) {
          avx2_paths.set(avx2);
          Mesh dropped;
          ASSERT_TRUE(clusterMesh(m, p, dropped).ok());
          SCOPED_TRACE(name + " w=" + std::to_string(p.cell_width) + " keep " + std::to_string(keep) +
                       (avx2 ? " avx2" : " scalar"));
          expectSameBits(dropped, reference);
        }
        avx2_paths.set(true);
        levels += reference.edgeCount() > 0;
      }
  }
  EXPECT_GE(levels, 30u);
}
