// Floating-cell clustering (Low & Tan 1997 §3.2, §4) and uniform subdivision (Rossignac & Borrel):
// invariants of the cells, checked by brute force against the paper's definitions.
#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/cluster.h"
#include "test_hooks.h"

using namespace scenelod;

namespace {

constexpr uint32_t kNone = 0xffffffffu;

bool inside(const glm::vec3& d, float w, CellShape shape) {
  const float h = 0.5f * w;
  return shape == CellShape::kCube ? (std::fabs(d.x) <= h && std::fabs(d.y) <= h && std::fabs(d.z) <= h)
                                   : glm::dot(d, d) <= h * h;
}

struct Case {
  LodMethod method;
  CellShape shape;
};

}  // namespace

TEST(FloatingCell, CellsSatisfyThePaperInvariants) {
  // the part alone is searched through a flat grid of heads over cubes of side w/2; a triangle some
  // way off makes the box of grid cubes too large for that at the finer widths (cubes of side w
  // instead), and one far away too large for any flat grid (the hash): all three must give cells
  // satisfying the definitions
  auto withTriangleAt = [](float d) {
    Mesh m = test::makeCadPart();
    Mesh t;
    t.positions = {{d, d, d}, {d + 0.5f, d, d}, {d, d + 0.5f, d}};
    t.triangles = {0, 1, 2};
    test::appendMesh(m, t);
    return m;
  };
  // pairs of points 0.0017 apart on a face-centred cubic lattice whose neighbours are just over 0.2
  // apart, with a triangle at 20 (so w = 0.4 takes the flat grid of cubes of side w): every pair is
  // a sphere cell at w = 0.4, about 10.5 per grid cube, so that cubes list more cells than one block
  // of 8 holds, and the second point of each pair must find its cell there
  auto lattice = [] {
    Mesh m;
    const float a = 0.29f;
    for (int x = 0; x < 5; ++x)
      for (int y = 0; y < 5; ++y)
        for (int z = 0; z < 5; ++z)
          for (glm::vec3 d : {glm::vec3(0.0f), glm::vec3(a / 2, a / 2, 0), glm::vec3(a / 2, 0, a / 2),
                              glm::vec3(0, a / 2, a / 2)}) {
            for (float e : {0.0f, 0.001f}) {
              m.points.push_back(uint32_t(m.positions.size()));
              m.positions.push_back(glm::vec3(float(x), float(y), float(z)) * a + d + glm::vec3(e));
            }
          }
    Mesh t;
    t.positions = {{20, 20, 20}, {20.5f, 20, 20}, {20, 20.5f, 20}};
    t.triangles = {0, 1, 2};
    test::appendMesh(m, t);
    return m;
  };
  for (const Mesh& m : {test::makeCadPart(), withTriangleAt(20.0f), withTriangleAt(4000.0f), lattice()}) {
    SCOPED_TRACE(m.vertexCount());
    PreparedMesh p;
    ClusterParams params;
    ASSERT_TRUE(prepareMesh(m, params, p).ok());
    for (Case c : {Case{LodMethod::kFloatingHeaviest, CellShape::kCube}, Case{LodMethod::kFloatingNearest, CellShape::kCube},
                   Case{LodMethod::kFloatingHeaviest, CellShape::kSphere},
                   Case{LodMethod::kFloatingNearest, CellShape::kSphere}}) {
      for (float w : {0.15f, 0.4f, 1.1f}) {
        params.method = c.method;
        params.cell_shape = c.shape;
        params.cell_width = w;
        ClusterAssignment a;
        ASSERT_TRUE(assignClusters(p, params, a).ok());
        const size_t nc = a.heaviest.size();
        SCOPED_TRACE(std::string(lodMethodName(c.method)) + " " + cellShapeName(c.shape) + " w=" + std::to_string(w));
        // cells are created heaviest first
        for (size_t k = 1; k < nc; ++k) EXPECT_GE(p.weights[a.heaviest[k - 1]], p.weights[a.heaviest[k]]);
        // no cell centre is inside another cell
        for (size_t i = 0; i < nc; ++i)
          for (size_t j = i + 1; j < nc; ++j)
            ASSERT_FALSE(inside(m.positions[a.heaviest[i]] - m.positions[a.heaviest[j]], w, c.shape)) << i << " " << j;
        // at most 8 cube cells (64 sphere cells) per grid cube of side w
        std::map<std::tuple<int, int, int>, int> per_cube;
        int most = 0;
        for (uint32_t v : a.heaviest) {
          const glm::vec3 q = glm::floor(m.positions[v] / w);
          most = std::max(most, ++per_cube[{int(q.x), int(q.y), int(q.z)}]);
        }
        EXPECT_LE(most, c.shape == CellShape::kCube ? 8 : 64);
        if (!m.points.empty() && c.shape == CellShape::kSphere && w == 0.4f) {
          EXPECT_GT(most, 8);  // see lattice()
        }
        // every referenced vertex is assigned, lies in its cell, and is assigned by the variant's rule
        // among the cells that existed when it was visited (centres earlier in the weight order)
        std::vector<size_t> rank(m.positions.size());
        for (size_t i = 0; i < p.order.size(); ++i) rank[p.order[i]] = i;
        for (size_t v = 0; v < m.positions.size(); ++v) {
          const uint32_t cl = a.cluster_of[v];
          ASSERT_NE(cl, kNone);
          ASSERT_LT(cl, nc);
          const glm::vec3 pv = m.positions[v];
          ASSERT_TRUE(inside(pv - m.positions[a.heaviest[cl]], w, c.shape));
          for (uint32_t o = 0; o < nc; ++o) {
            const glm::vec3 d = pv - m.positions[a.heaviest[o]];
            if (!inside(d, w, c.shape) || rank[a.heaviest[o]] > rank[v]) continue;
            if (c.method == LodMethod::kFloatingHeaviest) {
              ASSERT_GE(o, cl) << "vertex " << v << " is inside an earlier (heavier) cell";
            } else {
              const glm::vec3 dc = pv - m.positions[a.heaviest[cl]];
              ASSERT_GE(glm::dot(d, d), glm::dot(dc, dc)) << "vertex " << v << " has a nearer centre";
            }
          }
        }
      }
    }
  }
}

// The AVX2 paths (where the CPU has them) and the SSE2 ones choose the same cells, for both rules
// and shapes, on the flat grids of side w/2 and w (listed) at widths
// from a few vertices per cell to a few cells per mesh; the grid-aligned part puts vertices exactly
// on cube faces (the wide gathers); a triangle at 20 makes the sphere's box too large for cubes of
// side w/2 at w = 0.4 and 0.5 (cubes of side w with cells in blocks). On a CPU without AVX2 those
// runs take the SSE2 paths.
TEST(FloatingCell, SimdPathsChooseTheSameCells) {
  Mesh grid_part = test::makeCadPart();
  Mesh sphere = test::makeBumpySphere(60, 80);
  Mesh sphere_far = sphere;
  Mesh t;
  t.positions = {{20, 20, 20}, {20.5f, 20, 20}, {20, 20.5f, 20}};
  t.triangles = {0, 1, 2};
  test::appendMesh(sphere_far, t);
  for (const Mesh* m : {&grid_part, &sphere, &sphere_far}) {
    PreparedMesh p;
    ClusterParams params;
    ASSERT_TRUE(prepareMesh(*m, params, p).ok());
    for (Case c : {Case{LodMethod::kFloatingHeaviest, CellShape::kCube}, Case{LodMethod::kFloatingNearest, CellShape::kCube},
                   Case{LodMethod::kFloatingHeaviest, CellShape::kSphere},
                   Case{LodMethod::kFloatingNearest, CellShape::kSphere}}) {
      for (float w : {0.01f, 0.03f, 0.1f, 0.25f, 0.4f, 0.5f, 1.0f}) {
        SCOPED_TRACE(std::string(lodMethodName(c.method)) + " " + cellShapeName(c.shape) + " w=" + std::to_string(w));
        params.method = c.method;
        params.cell_shape = c.shape;
        params.cell_width = w;
        ClusterAssignment plain, wide;  // SSE2, AVX2
        {
          detail::HookGuard avx2(detail::setFloatingAvx2ForTest, false);
          ASSERT_TRUE(assignClusters(p, params, plain).ok());
          avx2.set(true);
          ASSERT_TRUE(assignClusters(p, params, wide).ok());
        }
        EXPECT_GT(plain.heaviest.size(), 1u);
        EXPECT_EQ(wide.heaviest, plain.heaviest);
        EXPECT_EQ(wide.cluster_of, plain.cluster_of);
      }
    }
  }
}

// The bricked grid of side w (cells in blocks under heads in bricks of 4 x 4 x 4 cubes, for boxes
// too large for flat heads) chooses the hash's cells, on the AVX2 and SSE2 paths, for both rules and
// shapes: on a sphere with a triangle at 20 (at w = 0.1 and 0.25 the box's flat heads would pass the
// dense budget, its bricks' table does not), on a lattice of point pairs holding about 10.5 sphere
// cells per grid cube (chained blocks, the general gather), on 2,197 small triangles 8 cubes apart
// (a brick each), on a finer sphere of 72,360 vertices and on 512 small spheres 16 cubes apart. The
// default takes it where the table and the bricks the vertices fill take at most 21 bytes per
// expected cell: the fine sphere; the small meshes' tables alone pass that (the hash), and the 512
// spheres' 4,096 bricks do (the hash, once counted). A limit of 2 bricks always gives the hash, one
// of 2^20 always the bricked grid.
TEST(FloatingCell, BrickedGridOfSideWChoosesTheHashsCells) {
  Mesh sphere_far = test::makeBumpySphere(60, 80);
  Mesh far_triangle;
  far_triangle.positions = {{20, 20, 20}, {20.5f, 20, 20}, {20, 20.5f, 20}};
  far_triangle.triangles = {0, 1, 2};
  test::appendMesh(sphere_far, far_triangle);
  Mesh lattice;
  const float a = 0.29f;
  for (int x = 0; x < 5; ++x)
    for (int y = 0; y < 5; ++y)
      for (int z = 0; z < 5; ++z)
        for (glm::vec3 d : {glm::vec3(0.0f), glm::vec3(a / 2, a / 2, 0), glm::vec3(a / 2, 0, a / 2), glm::vec3(0, a / 2, a / 2)})
          for (float e : {0.0f, 0.001f}) {
            lattice.points.push_back(uint32_t(lattice.positions.size()));
            lattice.positions.push_back(glm::vec3(float(x), float(y), float(z)) * a + d + glm::vec3(e));
          }
  Mesh far60 = far_triangle;
  for (glm::vec3& v : far60.positions) v += glm::vec3(40.0f);
  test::appendMesh(lattice, far60);
  Mesh scattered;  // w = 0.1: triangles 0.8 apart, each in a brick of its own
  for (int x = 0; x < 13; ++x)
    for (int y = 0; y < 13; ++y)
      for (int z = 0; z < 13; ++z) {
        const glm::vec3 o = glm::vec3(float(x), float(y), float(z)) * 0.8f;
        const uint32_t b = uint32_t(scattered.positions.size());
        scattered.positions.insert(scattered.positions.end(), {o, o + glm::vec3(0.03f, 0, 0), o + glm::vec3(0, 0.03f, 0.01f)});
        scattered.triangles.insert(scattered.triangles.end(), {b, b + 1, b + 2});
      }
  struct Run {
    const Mesh* mesh;
    float w;
    int grid;  // the grid the default settings take
  };
  const Mesh fine_sphere = test::makeBumpySphere(200, 360);  // 72,360 vertices: 32-bit heads
  Mesh spheres;  // w = 0.5: a sphere of diameter 1 every 8, on the bricks' corners (8 bricks each)
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 8; ++z) test::appendMesh(spheres, test::makeSphere(glm::vec3(x, y, z) * 8.0f, 0.5f, 12, 16));
  for (Run run : {Run{&sphere_far, 0.1f, 2}, Run{&sphere_far, 0.25f, 2}, Run{&lattice, 0.4f, 2}, Run{&scattered, 0.1f, 2},
                  Run{&fine_sphere, 0.02f, 1}, Run{&spheres, 0.5f, 3}}) {
    PreparedMesh p;
    ClusterParams params;
    ASSERT_TRUE(prepareMesh(*run.mesh, params, p).ok());
    for (Case c : {Case{LodMethod::kFloatingHeaviest, CellShape::kCube}, Case{LodMethod::kFloatingNearest, CellShape::kCube},
                   Case{LodMethod::kFloatingHeaviest, CellShape::kSphere},
                   Case{LodMethod::kFloatingNearest, CellShape::kSphere}}) {
      SCOPED_TRACE(std::string(lodMethodName(c.method)) + " " + cellShapeName(c.shape) + " w=" + std::to_string(run.w) +
                   " vertices " + std::to_string(run.mesh->vertexCount()));
      params.method = c.method;
      params.cell_shape = c.shape;
      params.cell_width = run.w;
      ClusterAssignment hash;
      int hash_grid = -1;
      {
        detail::HookGuard bricks(detail::setFloatingBlockBricksForTest, 0);
        ASSERT_TRUE(assignClusters(p, params, hash).ok());
        hash_grid = detail::lastFloatingGridForTest();
      }
      EXPECT_EQ(hash_grid, 2);
      EXPECT_GT(hash.heaviest.size(), 1u);
      if (run.mesh == &lattice && c.shape == CellShape::kSphere) {
        std::map<std::tuple<int, int, int>, int> per_cube;  // more cells in a cube than one block holds
        int most = 0;
        for (uint32_t v : hash.heaviest) {
          const glm::vec3 q = glm::floor(run.mesh->positions[v] / run.w);
          most = std::max(most, ++per_cube[{int(q.x), int(q.y), int(q.z)}]);
        }
        EXPECT_GT(most, 4);
      }
      for (bool avx2 : {true, false})
        for (int mode : {-1, 2, 1 << 20}) {
          SCOPED_TRACE(std::string(avx2 ? "avx2" : "sse2") + " bricks " + std::to_string(mode));
          ClusterAssignment other;
          int grid = -1;
          {
            detail::HookGuard avx2_paths(detail::setFloatingAvx2ForTest, avx2);
            detail::HookGuard bricks(detail::setFloatingBlockBricksForTest, mode);
            ASSERT_TRUE(assignClusters(p, params, other).ok());
            grid = detail::lastFloatingGridForTest();
          }
          EXPECT_EQ(grid, mode < 0 ? run.grid : mode == 2 ? 3 : 1);
          EXPECT_EQ(other.heaviest, hash.heaviest);
          EXPECT_EQ(other.cluster_of, hash.cluster_of);
        }
    }
  }
}

TEST(UniformCluster, ClustersAreGridCellsOfTheBoundingBox) {
  Mesh m = test::makeSphere({0.3f, -0.2f, 0.1f}, 1.0f, 12, 16);
  PreparedMesh p;
  ClusterParams params;
  params.method = LodMethod::kUniform;
  params.cell_width = 0.37f;
  ASSERT_TRUE(prepareMesh(m, params, p).ok());
  ClusterAssignment a;
  ASSERT_TRUE(assignClusters(p, params, a).ok());
  std::map<std::tuple<int, int, int>, uint32_t> cell_cluster;
  for (size_t v = 0; v < m.positions.size(); ++v) {
    const glm::vec3 q = glm::floor((m.positions[v] - p.bounds.min) / params.cell_width);
    const auto key = std::make_tuple(int(q.x), int(q.y), int(q.z));
    auto it = cell_cluster.find(key);
    if (it == cell_cluster.end()) cell_cluster[key] = a.cluster_of[v];
    else EXPECT_EQ(it->second, a.cluster_of[v]);  // one cluster per grid cell
  }
  EXPECT_EQ(cell_cluster.size(), a.heaviest.size());  // and one grid cell per cluster
}

// Fig. 4 / §3.2.3: V1 heavier than V2; V3 inside both cells, nearer V2. The thin triangle (P, V3, V2)
// stays a triangle, widened from |V3 V2| to |R1 R2|, when V3 joins the heaviest cell; it collapses
// into an edge when V3 joins the nearest centre.
TEST(FloatingCell, NearestCentreVariantCollapsesTheThinTriangleOfFigure4) {
  Mesh m;
  //             V1          V2            V3             P            Q1          Q2
  m.positions = {{0, 0, 0}, {0.9f, 0, 0}, {0.48f, 0.02f, 0}, {0.7f, 4, 0}, {-3, 0, 0}, {-3, 1, 0}};
  m.triangles = {3, 2, 1,    // the thin triangle P, V3, V2
                 0, 4, 5};   // a triangle that makes V1 referenced
  PreparedMesh p;
  ClusterParams params;
  params.synthesis = Synthesis::kHeaviest;
  params.cell_width = 1.0f;
  ASSERT_TRUE(prepareMesh(m, params, p).ok());
  // the rule under test is the assignment, so fix the weight order V1 > P > Q1 > Q2 > V2 > V3
  p.order = {0, 3, 4, 5, 1, 2};
  p.sorted_positions.clear();
  for (uint32_t v : p.order) p.sorted_positions.push_back(m.positions[v]);
  p.weights = {1.0f, 0.5f, 0.4f, 0.9f, 0.8f, 0.7f};

  params.method = LodMethod::kFloatingHeaviest;
  ClusterAssignment a;
  ASSERT_TRUE(assignClusters(p, params, a).ok());
  EXPECT_EQ(a.cluster_of[2], a.cluster_of[0]);  // V3 joins V1's cell
  Mesh heavy;
  ASSERT_TRUE(clusterPrepared(p, params, heavy).ok());
  ASSERT_EQ(heavy.triangleCount(), 2u);
  EXPECT_EQ(heavy.edgeCount(), 0u);
  // the side of P's triangle opposite P, after clustering, against |V3 V2| before
  float base_after = -1.0f;
  const glm::vec3 P = m.positions[3];
  for (size_t t = 0; t < 2; ++t)
    for (int k = 0; k < 3; ++k)
      if (glm::length(heavy.positions[heavy.triangles[3 * t + k]] - P) < 1e-6f)
        base_after = glm::length(heavy.positions[heavy.triangles[3 * t + (k + 1) % 3]] -
                                 heavy.positions[heavy.triangles[3 * t + (k + 2) % 3]]);
  const float base_before = glm::length(m.positions[2] - m.positions[1]);
  ASSERT_GT(base_after, 0.0f) << "no output triangle has P as a corner";
  EXPECT_GT(base_after, 2.0f * base_before);  // |R1 R2| = |V1 V2| = 0.9 against 0.42

  params.method = LodMethod::kFloatingNearest;
  ASSERT_TRUE(assignClusters(p, params, a).ok());
  EXPECT_EQ(a.cluster_of[2], a.cluster_of[1]);  // V3 joins the nearer V2
  Mesh nearest;
  ASSERT_TRUE(clusterPrepared(p, params, nearest).ok());
  EXPECT_EQ(nearest.triangleCount(), 1u);  // only the far triangle remains
  ASSERT_EQ(nearest.edgeCount(), 1u);      // the thin triangle became the edge P-V2
  const glm::vec3 e0 = nearest.positions[nearest.edges[0]], e1 = nearest.positions[nearest.edges[1]];
  EXPECT_NEAR(std::min(glm::length(e0 - m.positions[3]), glm::length(e1 - m.positions[3])), 0.0f, 1e-6f);
  EXPECT_NEAR(std::min(glm::length(e0 - m.positions[1]), glm::length(e1 - m.positions[1])), 0.0f, 1e-6f);
}
