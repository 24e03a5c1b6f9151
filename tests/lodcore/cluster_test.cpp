// clusterMesh as a whole: output validity for every method and option, the consistency experiment of
// Low & Tan 1997 §3.2.2, synthesis bounds, bad input.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <tuple>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lodcore/generated_meshes.h"
#include "scenelod/eval/consistency.h"
#include "scenelod/lodcore/cluster.h"
#include "test_hooks.h"
#include "test_support.h"

using namespace scenelod;

namespace {

void expectValidOutput(const Mesh& in, const Mesh& out) {
  ASSERT_TRUE(validateMesh(out, "output").ok()) << validateMesh(out, "output").message;
  EXPECT_LE(out.triangleCount(), in.triangleCount());
  EXPECT_EQ(out.normals.size(), out.positions.size());
  for (size_t t = 0; t < out.triangleCount(); ++t) {
    const uint32_t a = out.triangles[3 * t], b = out.triangles[3 * t + 1], c = out.triangles[3 * t + 2];
    ASSERT_TRUE(a != b && b != c && a != c) << "degenerate triangle " << t;
  }
  for (size_t e = 0; e < out.edgeCount(); ++e) ASSERT_NE(out.edges[2 * e], out.edges[2 * e + 1]);
  for (const glm::vec3& n : out.normals) ASSERT_NEAR(glm::length(n), 1.0f, 1e-3f);
  EXPECT_EQ(out.edge_thickness.size(), out.edgeCount());
  EXPECT_TRUE(out.uvs.empty());
}

}  // namespace

TEST(ClusterMesh, OutputIsValidForEveryMethodShapeAndSynthesis) {
  Mesh m = test::makeCadPart();
  m.colors.assign(m.positions.size(), glm::vec3(0.2f, 0.4f, 0.6f));
  for (LodMethod method : {LodMethod::kUniform, LodMethod::kFloatingHeaviest, LodMethod::kFloatingNearest})
    for (CellShape shape : {CellShape::kCube, CellShape::kSphere})
      for (Synthesis s : {Synthesis::kMean, Synthesis::kHeaviest, Synthesis::kQuadric})
        for (float w : {0.05f, 0.3f, 2.0f}) {
          ClusterParams p;
          p.method = method;
          p.cell_shape = shape;
          p.synthesis = s;
          p.cell_width = w;
          Mesh out;
          float err = -1.0f;
          SCOPED_TRACE(std::string(lodMethodName(method)) + " " + cellShapeName(shape) + " " + synthesisName(s) +
                       " w=" + std::to_string(w));
          ASSERT_TRUE(clusterMesh(m, p, out, &err).ok());
          expectValidOutput(m, out);
          // a vertex and its representative share a cell of width w: at most its diagonal apart
          EXPECT_LE(err, w * std::sqrt(3.0f) * 1.0001f);
          EXPECT_GE(err, 0.0f);
          // area-weighted average of one colour is that colour
          ASSERT_EQ(out.colors.size(), out.positions.size());
          for (const glm::vec3& c : out.colors) EXPECT_NEAR(glm::length(c - glm::vec3(0.2f, 0.4f, 0.6f)), 0.0f, 1e-4f);
        }
}

TEST(ClusterMesh, HeaviestSynthesisPutsRepresentativesOnTheCellCentres) {
  const Mesh m = test::makeSphere({0, 0, 0}, 1.0f, 16, 24);
  ClusterParams p;
  p.synthesis = Synthesis::kHeaviest;
  p.cell_width = 0.4f;
  Mesh out;
  ASSERT_TRUE(clusterMesh(m, p, out).ok());
  for (const glm::vec3& v : out.positions) EXPECT_NEAR(glm::length(v), 1.0f, 1e-5f);  // original vertices
}

TEST(ClusterMesh, QuadricSynthesisKeepsBoxCornersAndFaces) {
  // every cluster of a box lies on its faces; the quadric minimiser keeps the corners exactly and
  // the face and edge clusters on their planes (the singular directions stay at the mean)
  const Mesh box = test::makeBox({0, 0, 0}, {2, 2, 2}, 8);
  ClusterParams p;
  p.synthesis = Synthesis::kQuadric;
  p.cell_width = 0.55f;
  Mesh out;
  ASSERT_TRUE(clusterMesh(box, p, out).ok());
  int corners = 0;
  for (const glm::vec3& v : out.positions) {
    const glm::vec3 d = glm::min(glm::abs(v), glm::abs(v - glm::vec3(2.0f)));
    EXPECT_NEAR(std::min({d.x, d.y, d.z}), 0.0f, 1e-4f) << v.x << " " << v.y << " " << v.z;
    if (d.x < 1e-4f && d.y < 1e-4f && d.z < 1e-4f) ++corners;
  }
  EXPECT_GE(corners, 8);  // the 8 corners (split by normals into several vertices each)
}

TEST(ClusterMesh, CreaseAngleSplitsVerticesOfSharpEdges) {
  const Mesh box = test::makeBox({0, 0, 0}, {1, 1, 1}, 1);
  ClusterParams p;
  p.cell_width = 0.1f;  // keeps the box
  Mesh out;
  ASSERT_TRUE(clusterMesh(box, p, out).ok());
  EXPECT_EQ(out.triangleCount(), 12u);
  EXPECT_EQ(out.positions.size(), 24u);  // each corner split into 3 (one per face)
  p.crease_angle_deg = 120.0f;           // 90 degree edges are now smooth
  ASSERT_TRUE(clusterMesh(box, p, out).ok());
  EXPECT_EQ(out.positions.size(), 8u);
}

// Each output corner's normal is the normalised area-weighted sum of the cluster's faces within the
// crease angle of the corner's face (Low & Tan §2 step 6), and corners whose faces take the same set
// share one vertex, at every crease angle (the output pass takes shortcuts for smooth clusters).
TEST(ClusterMesh, CornerNormalsFollowTheCreaseRule) {
  Mesh cad = test::makeCadPart();
  Mesh bumpy = test::makeSphere({0, 0, 0}, 1.0f, 24, 32);
  for (glm::vec3& v : bumpy.positions) v *= 1.0f + 0.08f * std::sin(11.0f * v.x) * std::cos(9.0f * v.y + 3.0f * v.z);
  for (const Mesh* m : {&cad, &bumpy})
    for (float w : {0.08f, 0.25f})
      for (float angle : {0.0f, 20.0f, 45.0f, 60.0f, 90.0f, 150.0f, 180.0f}) {
        ClusterParams p;
        p.cell_width = w;
        p.crease_angle_deg = angle;
        Mesh out;
        ASSERT_TRUE(clusterMesh(*m, p, out).ok());
        SCOPED_TRACE("w " + std::to_string(w) + " crease " + std::to_string(angle));
        const float cos_crease = std::cos(angle * 3.14159265358979f / 180.0f);
        const size_t tn = out.triangleCount();
        std::vector<glm::vec3> face(tn);  // area-weighted (twice the area)
        for (size_t t = 0; t < tn; ++t) {
          const glm::vec3& a = out.positions[out.triangles[3 * t]];
          face[t] = glm::cross(out.positions[out.triangles[3 * t + 1]] - a, out.positions[out.triangles[3 * t + 2]] - a);
        }
        // the corners of one cluster: split copies of a vertex keep its position
        std::vector<uint32_t> corner_order(3 * tn);
        for (uint32_t i = 0; i < 3 * tn; ++i) corner_order[i] = i;
        auto key = [&](uint32_t i) {
          const glm::vec3& q = out.positions[out.triangles[i]];
          return std::make_tuple(q.x, q.y, q.z);
        };
        std::stable_sort(corner_order.begin(), corner_order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
        size_t checked = 0;
        for (size_t g = 0; g < corner_order.size();) {
          size_t ge = g + 1;
          while (ge < corner_order.size() && key(corner_order[ge]) == key(corner_order[g])) ++ge;
          std::vector<std::vector<bool>> taken(ge - g);
          bool clear = true;  // no pair within 1e-3 of the threshold, where rounding may decide
          for (size_t i = g; i < ge; ++i) {
            const glm::vec3 ui = glm::normalize(face[corner_order[i] / 3]);
            glm::vec3 sum(0.0f);
            for (size_t j = g; j < ge; ++j) {
              const glm::vec3 uj = glm::normalize(face[corner_order[j] / 3]);
              const float d = glm::dot(ui, uj);
              if (i != j && std::fabs(d - cos_crease) < 1e-3f) clear = false;
              taken[i - g].push_back(i == j || d >= cos_crease);
              if (taken[i - g].back()) sum += face[corner_order[j] / 3];
            }
            const glm::vec3 n = out.normals[out.triangles[corner_order[i]]];
            if (clear && glm::length(sum) > 1e-6f) {
              EXPECT_GT(glm::dot(n, glm::normalize(sum)), 0.9999f);
            }
          }
          if (clear) {
            for (size_t i = g; i < ge; ++i)
              for (size_t j = g; j < ge; ++j)
                if (taken[i - g] == taken[j - g]) {
                  EXPECT_EQ(out.triangles[corner_order[i]], out.triangles[corner_order[j]]);
                  ++checked;
                }
          }
          g = ge;
        }
        // (at 0 degrees the coplanar faces lie on the threshold and are skipped)
        if (angle > 0.0f) {
          EXPECT_GT(checked, tn);
        }
      }
}

// §3.2.2 / plate 5: adding an object far away changes the bounding box. Floating cells sit on the
// heaviest vertices and do not move; uniform cells are anchored to the bounding box and shift.
TEST(ClusterMesh, FarAwayObjectChangesUniformButNotFloatingCells) {
  const Mesh part = test::makeCadPart();
  Mesh scene = part;
  test::appendMesh(scene, test::makeSphere({-37.3f, -41.7f, -53.1f}, 2.0f, 12, 16));
  Aabb region = computeBounds(part);
  region.min -= glm::vec3(1.0f);
  region.max += glm::vec3(1.0f);
  for (LodMethod method : {LodMethod::kFloatingNearest, LodMethod::kFloatingHeaviest, LodMethod::kUniform}) {
    ClusterParams p;
    p.method = method;
    p.cell_width = 0.3f;
    Mesh a, b;
    ASSERT_TRUE(clusterMesh(part, p, a).ok());
    ASSERT_TRUE(clusterMesh(scene, p, b).ok());
    const eval::TriangleChangeCount count = eval::countChangedTriangles(a, b, region, 1e-5f);
    SCOPED_TRACE(lodMethodName(method));
    ASSERT_GT(count.compared, 100u);
    if (method == LodMethod::kUniform) EXPECT_GT(count.changed, count.compared / 5);
    else EXPECT_LE(count.changed, count.compared / 100);
  }
}

TEST(ClusterMesh, BadInputGivesClearErrors) {
  const Mesh good = test::makeSphere({0, 0, 0}, 1.0f, 6, 8);
  Mesh out;
  ClusterParams p;
  for (float w : {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    p.cell_width = w;
    const Error e = clusterMesh(good, p, out);
    EXPECT_EQ(e.status, Status::kInvalidArgument) << w;
    EXPECT_NE(e.message.find("cell width"), std::string::npos) << e.message;
  }
  p.cell_width = 1e-30f;  // 2^30 cells along an axis would overflow the grid
  EXPECT_EQ(clusterMesh(good, p, out).status, Status::kInvalidArgument);
  p.cell_width = 0.5f;
  Mesh nan = good;
  nan.positions[3].x = std::numeric_limits<float>::quiet_NaN();
  Error e = clusterMesh(nan, p, out);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("vertex 3"), std::string::npos) << e.message;
  Mesh inf = good;
  inf.positions[1].z = std::numeric_limits<float>::infinity();
  EXPECT_EQ(clusterMesh(inf, p, out).status, Status::kInvalidMesh);
  Mesh range = good;
  range.triangles[5] = 1000;
  e = clusterMesh(range, p, out);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("1000"), std::string::npos) << e.message;
  p.method = LodMethod::kZhang;
  EXPECT_EQ(clusterMesh(good, p, out).status, Status::kInvalidArgument);
}

TEST(ClusterMesh, EmptyMeshGivesEmptyResult) {
  Mesh out;
  ClusterParams p;
  p.cell_width = 1.0f;
  Mesh empty;
  ASSERT_TRUE(clusterMesh(empty, p, out).ok());
  EXPECT_TRUE(out.empty());
  Mesh unreferenced;
  unreferenced.positions = {{0, 0, 0}, {1, 1, 1}};
  ASSERT_TRUE(clusterMesh(unreferenced, p, out).ok());
  EXPECT_TRUE(out.empty());
  EXPECT_TRUE(out.positions.empty());
}

TEST(ClusterMesh, DuplicateVerticesMerge) {
  const Mesh single_in = test::makeSphere({0, 0, 0}, 1.0f, 8, 12);
  Mesh m = single_in;
  // duplicate every vertex and build a second copy of the sphere on the duplicates
  const size_t n = m.positions.size(), tn = m.triangles.size();
  for (size_t i = 0; i < n; ++i) m.positions.push_back(m.positions[i]);
  for (size_t i = 0; i < tn; ++i) m.triangles.push_back(m.triangles[i] + uint32_t(n));
  ClusterParams p;
  p.cell_width = 0.3f;
  Mesh out, single;
  ASSERT_TRUE(clusterMesh(m, p, out).ok());
  expectValidOutput(m, out);
  ASSERT_TRUE(clusterMesh(single_in, p, single).ok());
  // the copy lands in the same clusters, its triangles are duplicates of the same orientation
  EXPECT_EQ(out.triangleCount(), single.triangleCount());
  EXPECT_EQ(out.vertexCount(), single.vertexCount());
}

TEST(ClusterMesh, DegenerateTrianglesAreHandled) {
  Mesh m = test::makeSphere({0, 0, 0}, 1.0f, 8, 12);
  // zero-area triangles: a repeated index, and three collinear points (two of them close)
  m.positions.push_back({3, 0, 0});
  m.positions.push_back({3.05f, 0, 0});
  m.positions.push_back({5, 0, 0});
  const uint32_t a = uint32_t(m.positions.size() - 3);
  m.triangles.insert(m.triangles.end(), {0, 0, 1, a, a + 1, a + 2});
  ClusterParams p;
  p.cell_width = 0.3f;
  Mesh out;
  ASSERT_TRUE(clusterMesh(m, p, out).ok());
  expectValidOutput(m, out);
  EXPECT_EQ(out.edgeCount(), 1u);  // the collinear triangle became the edge 3-5
  ASSERT_EQ(out.edge_thickness.size(), 1u);
  EXPECT_TRUE(std::isfinite(out.edge_thickness[0]));
}

namespace {

using test::sameBits;

}  // namespace

// The AVX2 variants (where the CPU has them) give the baseline's bits: every array of the output and
// the level's maximum displacement, for each synthesis, fine and coarse levels, with
// colours, crease splits and a sphere cell; on a CPU without AVX2 both runs take the baseline.
TEST(ClusterMesh, Avx2PathsGiveTheBaselineBits) {
  Mesh bumpy = test::makeBumpySphere(90, 120);
  Mesh cad = test::makeCadPart();
  cad.colors.resize(cad.positions.size());
  for (size_t i = 0; i < cad.colors.size(); ++i)
    cad.colors[i] = glm::vec3(float(i % 7) / 7.0f, float(i % 5) / 5.0f, float(i % 3) / 3.0f);
  detail::HookGuard avx2(detail::useAvx2Paths, true);
  size_t levels = 0, split = 0;
  for (const Mesh* m : {&bumpy, &cad})
    for (Synthesis s : {Synthesis::kQuadric, Synthesis::kMean, Synthesis::kHeaviest})
      for (CellShape shape : {CellShape::kCube, CellShape::kSphere})
        for (float w : {0.01f, 0.03f, 0.1f, 0.4f}) {
          ClusterParams p;
          p.synthesis = s;
          p.cell_shape = shape;
          p.cell_width = w;
          p.crease_angle_deg = 40.0f;
          Mesh wide, base;
          float wide_error = -1.0f, base_error = -2.0f;  // the level's maximum vertex displacement
          avx2.set(true);
          ASSERT_TRUE(clusterMesh(*m, p, wide, &wide_error).ok());
          avx2.set(false);
          ASSERT_TRUE(clusterMesh(*m, p, base, &base_error).ok());
          SCOPED_TRACE(std::string(synthesisName(s)) + " " + cellShapeName(shape) + " w=" + std::to_string(w));
          ASSERT_GT(base.triangleCount(), 0u);
          EXPECT_GT(base_error, 0.0f);
          EXPECT_TRUE(sameBits(std::vector<float>{wide_error}, std::vector<float>{base_error}));
          EXPECT_TRUE(sameBits(wide.positions, base.positions));
          EXPECT_TRUE(sameBits(wide.normals, base.normals));
          EXPECT_TRUE(sameBits(wide.colors, base.colors));
          EXPECT_TRUE(sameBits(wide.triangles, base.triangles));
          EXPECT_TRUE(sameBits(wide.edges, base.edges));
          EXPECT_TRUE(sameBits(wide.edge_thickness, base.edge_thickness));
          EXPECT_TRUE(sameBits(wide.points, base.points));
          ++levels;
          split += base.vertexCount() > base.triangleCount() / 2 + 2;  // crease copies (closed meshes: V ~ T / 2)
        }
  // levels past the prefetch thresholds: a single pass whose sums exceed 1 MB (w = 0.04: 17 k
  // clusters of 120 k vertices, 34 k triangles) and an output of more than 64 k triangles (w = 0.012)
  const Mesh big = test::makeBumpySphere(300, 400);
  for (float w : {0.04f, 0.012f}) {
    ClusterParams p;
    p.cell_width = w;
    Mesh wide, base;
    avx2.set(true);
    ASSERT_TRUE(clusterMesh(big, p, wide).ok());
    avx2.set(false);
    ASSERT_TRUE(clusterMesh(big, p, base).ok());
    EXPECT_GT(base.triangleCount(), w > 0.02f ? 30000u : 65536u);
    EXPECT_TRUE(sameBits(wide.positions, base.positions));
    EXPECT_TRUE(sameBits(wide.normals, base.normals));
    EXPECT_TRUE(sameBits(wide.triangles, base.triangles));
  }
  EXPECT_EQ(levels, 48u);
  EXPECT_GT(split, 0u);  // the CAD part's sharp edges split vertices in some levels
}

namespace {

// a level's triangles as sorted position triples, each the least of its three rotations (its
// winding kept), with the corners' normals alongside, in the same order
struct CornerSet {
  std::vector<std::array<float, 18>> tris;  // 3 x (position, normal)
};
CornerSet cornerSet(const Mesh& m) {
  CornerSet s;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    std::array<std::array<float, 6>, 3> c;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.triangles[3 * t + k];
      c[k] = {m.positions[v].x, m.positions[v].y, m.positions[v].z, m.normals[v].x, m.normals[v].y, m.normals[v].z};
    }
    auto positions = [](const std::array<std::array<float, 6>, 3>& r) {
      return std::make_tuple(r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2]);
    };
    std::array<std::array<float, 6>, 3> best = c;
    for (int r = 1; r < 3; ++r) {
      std::rotate(c.begin(), c.begin() + 1, c.end());
      if (positions(c) < positions(best)) best = c;
    }
    std::array<float, 18> flat;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 6; ++j) flat[6 * k + j] = best[k][j];
    s.tris.push_back(flat);
  }
  std::sort(s.tris.begin(), s.tris.end(), [](const std::array<float, 18>& a, const std::array<float, 18>& b) {
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        if (a[6 * k + j] != b[6 * k + j]) return a[6 * k + j] < b[6 * k + j];
    return false;
  });
  return s;
}

}  // namespace

// A level renumbers its clusters by first vertex index where they are many (cluster_mesh.cpp): the
// same primitives at the same positions, the same error and cluster count; only the vertices' order
// moves, and with it the corner a triangle starts at, so normals may differ in their last bits.
TEST(ClusterMesh, RenumberingClustersKeepsTheLevel) {
  const Mesh m = test::makeBumpySphere(300, 400);  // 120 k vertices
  PreparedMesh p;
  ASSERT_TRUE(prepareMesh(m, ClusterParams(), p).ok());
  detail::HookGuard renumbering(detail::setRenumberingForTest, -1);
  size_t renumbered_by_default = 0, kept_by_default = 0;
  for (LodMethod method : {LodMethod::kFloatingHeaviest, LodMethod::kFloatingNearest, LodMethod::kUniform})
    for (float w : {0.006f, 0.04f}) {
      ClusterParams params;
      params.method = method;
      params.cell_width = w;
      Mesh on, off, by_default;
      ClusterStats on_stats, off_stats;
      SCOPED_TRACE(std::string(lodMethodName(method)) + " w=" + std::to_string(w));
      renumbering.set(1);
      ASSERT_TRUE(clusterPrepared(p, params, on, &on_stats).ok());
      renumbering.set(0);
      ASSERT_TRUE(clusterPrepared(p, params, off, &off_stats).ok());
      renumbering.set(-1);
      ASSERT_TRUE(clusterPrepared(p, params, by_default).ok());
      ASSERT_GT(off.triangleCount(), 1000u);
      EXPECT_EQ(on_stats.cluster_count, off_stats.cluster_count);
      EXPECT_TRUE(sameBits(std::vector<float>{on_stats.max_error}, std::vector<float>{off_stats.max_error}));
      EXPECT_EQ(on.vertexCount(), off.vertexCount());
      EXPECT_EQ(on.edgeCount(), off.edgeCount());
      EXPECT_EQ(on.pointCount(), off.pointCount());
      // the same positions, as a multiset, and the same triangles
      std::vector<glm::vec3> pa = on.positions, pb = off.positions;
      auto lex = [](const glm::vec3& a, const glm::vec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); };
      std::sort(pa.begin(), pa.end(), lex);
      std::sort(pb.begin(), pb.end(), lex);
      EXPECT_TRUE(sameBits(pa, pb));
      const CornerSet a = cornerSet(on), b = cornerSet(off);
      ASSERT_EQ(a.tris.size(), b.tris.size());
      float normal_diff = 0.0f;
      size_t position_mismatches = 0;
      for (size_t t = 0; t < a.tris.size(); ++t)
        for (int k = 0; k < 3; ++k) {
          for (int j = 0; j < 3; ++j) position_mismatches += a.tris[t][6 * k + j] != b.tris[t][6 * k + j];
          for (int j = 3; j < 6; ++j) normal_diff = std::max(normal_diff, std::fabs(a.tris[t][6 * k + j] - b.tris[t][6 * k + j]));
        }
      EXPECT_EQ(position_mismatches, 0u);
      EXPECT_LT(normal_diff, 1e-4f);
      // the default renumbers where the clusters are many (32,768 or more) and leaves the others
      const bool many = off_stats.cluster_count >= 32768;
      const Mesh& expected = many ? on : off;
      EXPECT_TRUE(sameBits(by_default.positions, expected.positions));
      EXPECT_TRUE(sameBits(by_default.triangles, expected.triangles));
      (many ? renumbered_by_default : kept_by_default) += 1;
      // renumbered, the output's vertices differ in order from the creation order's
      if (many) {
        EXPECT_FALSE(sameBits(on.positions, off.positions));
      }
    }
  EXPECT_GT(renumbered_by_default, 0u);  // both sides of the threshold were exercised
  EXPECT_GT(kept_by_default, 0u);
}
