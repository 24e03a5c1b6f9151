#include "scenelod/lodcore/zhang.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <tuple>
#include <utility>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "scenelod/lodcore/obj_io.h"
#include "test_support.h"

using namespace scenelod;

namespace {

// icosphere of radius 1 around the origin: closed, genus 0, 20 * 4^level triangles
Mesh icosphere(int level) {
  Mesh m;
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  m.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : m.positions) p = glm::normalize(p);
  m.triangles = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
                 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.positions.push_back(glm::normalize(m.positions[a] + m.positions[b]));
      const uint32_t id = static_cast<uint32_t>(m.positions.size() - 1);
      mid[key] = id;
      return id;
    };
    std::vector<uint32_t> next;
    for (size_t i = 0; i < m.triangles.size(); i += 3) {
      const uint32_t a = m.triangles[i], b = m.triangles[i + 1], c = m.triangles[i + 2];
      const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    m.triangles = next;
  }
  return m;
}

// axis-aligned cube [-1,1]^3 with an n x n grid on each face, welded: closed, 12 n^2 triangles
Mesh gridCube(int n) {
  Mesh m;
  std::map<std::tuple<int, int, int>, uint32_t> ids;
  auto vertex = [&](int x, int y, int z) {
    const auto key = std::make_tuple(x, y, z);
    auto it = ids.find(key);
    if (it != ids.end()) return it->second;
    m.positions.push_back(glm::vec3(x, y, z) * (2.0f / n) - glm::vec3(1.0f));
    return ids[key] = static_cast<uint32_t>(m.positions.size() - 1);
  };
  // each face: fixed axis a at 0 or n, the two others (u, v) ordered so that u x v points outwards
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          auto at = [&](int u, int v) {
            int c[3];
            c[axis] = side * n;
            c[ua] = u;
            c[va] = v;
            return vertex(c[0], c[1], c[2]);
          };
          const uint32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
          if (side == 1) m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
          else m.triangles.insert(m.triangles.end(), {a, c, b, a, d, c});
        }
    }
  return m;
}

// flat open n x n grid in z = 0, normals +z
Mesh flatGrid(int n) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.positions.push_back({float(i), float(j), 0.0f});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
    }
  return m;
}

// torus (major radius 1, minor 0.35), closed, genus 1
Mesh torus(int nu, int nv) {
  Mesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const float u = 2.0f * 3.14159265f * i / nu, v = 2.0f * 3.14159265f * j / nv;
      m.positions.push_back({(1.0f + 0.35f * std::cos(v)) * std::cos(u), (1.0f + 0.35f * std::cos(v)) * std::sin(u),
                             0.35f * std::sin(v)});
    }
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const uint32_t a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv,
                     d = i * nv + (j + 1) % nv;
      m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
    }
  return m;
}

glm::vec3 faceNormal(const Mesh& m, size_t t) {
  const glm::vec3 a = m.positions[m.triangles[3 * t]], b = m.positions[m.triangles[3 * t + 1]],
                  c = m.positions[m.triangles[3 * t + 2]];
  return glm::cross(b - a, c - a);
}

// indices in range, no repeated index, no zero-area triangle
void expectValid(const Mesh& m) {
  ASSERT_TRUE(validateMesh(m, "result").ok()) << validateMesh(m, "result").message;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const uint32_t a = m.triangles[3 * t], b = m.triangles[3 * t + 1], c = m.triangles[3 * t + 2];
    EXPECT_TRUE(a != b && b != c && a != c) << "triangle " << t << " repeats a vertex";
    EXPECT_GT(glm::length(faceNormal(m, t)), 0.0f) << "triangle " << t << " has zero area";
  }
}

// every directed edge once and its twin present: closed, edge-manifold, consistently oriented
void expectClosedManifold(const Mesh& m) {
  std::set<std::pair<uint32_t, uint32_t>> directed;
  for (size_t t = 0; t < m.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) {
      const auto e = std::make_pair(m.triangles[3 * t + k], m.triangles[3 * t + (k + 1) % 3]);
      EXPECT_TRUE(directed.insert(e).second) << "directed edge " << e.first << "-" << e.second << " used twice";
    }
  for (const auto& e : directed)
    EXPECT_TRUE(directed.count({e.second, e.first})) << "edge " << e.first << "-" << e.second << " is open";
}

long eulerCharacteristic(const Mesh& m) {
  std::vector<uint64_t> edges;
  std::vector<uint32_t> verts(m.triangles);
  for (size_t t = 0; t < m.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) {
      const auto e = std::minmax(m.triangles[3 * t + k], m.triangles[3 * t + (k + 1) % 3]);
      edges.push_back(uint64_t(e.first) << 32 | e.second);
    }
  std::sort(edges.begin(), edges.end());
  std::sort(verts.begin(), verts.end());
  const long e = std::unique(edges.begin(), edges.end()) - edges.begin();
  const long v = std::unique(verts.begin(), verts.end()) - verts.begin();
  return v - e + static_cast<long>(m.triangleCount());
}

const ZhangVertexMeasures& measureOf(const std::vector<ZhangVertexMeasures>& all, size_t v) { return all.at(v); }

}  // namespace

TEST(ZhangDefinitions, FlatInteriorVertexHasZeroVisionAndHeight) {
  const Mesh m = flatGrid(4);
  std::vector<ZhangVertexMeasures> ms;
  ASSERT_TRUE(computeZhangMeasures(m, ZhangParams{}, ms).ok());
  const auto& c = measureOf(ms, 2 * 5 + 2);  // the centre vertex
  EXPECT_EQ(c.characteristic, 0u);
  EXPECT_FLOAT_EQ(c.vision, 0.0f);
  EXPECT_FLOAT_EQ(c.super_height, 0.0f);
  EXPECT_FLOAT_EQ(c.super_volume, 0.0f);
  EXPECT_NEAR(c.super_area, 3.0f, 1e-5f);  // the hexagon left by the centre: its six half-squares
  EXPECT_EQ(c.vertex_class, ZhangVertexClass::kSimple);
  // boundary vertices: the two boundary neighbours appear once each, C(V) = 2
  EXPECT_EQ(measureOf(ms, 2).characteristic, 2u);
  EXPECT_EQ(measureOf(ms, 2).vertex_class, ZhangVertexClass::kEdge);
  EXPECT_EQ(measureOf(ms, 0).vertex_class, ZhangVertexClass::kEdge);
}

TEST(ZhangDefinitions, PyramidApexMatchesClosedForm) {
  // apex (0,0,h) over the square (+-1,+-1,0): four faces of area sqrt(1+h^2) at angle atan(h) to +z
  const float h = 0.75f;
  Mesh m;
  m.positions = {{0, 0, h}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, {-1, -1, 0}};
  m.triangles = {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1};
  std::vector<ZhangVertexMeasures> ms;
  ASSERT_TRUE(computeZhangMeasures(m, ZhangParams{}, ms).ok());
  const auto& a = ms[0];
  EXPECT_EQ(a.characteristic, 0u);
  EXPECT_NEAR(a.vision, std::atan(h) * std::sqrt(1.0f + h * h), 1e-5f);
  EXPECT_NEAR(a.max_angle_rad, std::atan(h), 1e-5f);
  EXPECT_NEAR(a.super_area, 4.0f, 1e-5f);           // the planar square ring
  EXPECT_NEAR(a.super_volume, 4.0f * h / 3.0f, 1e-5f);  // the pyramid
  EXPECT_NEAR(a.super_height, h, 1e-5f);
  EXPECT_EQ(a.vertex_class, ZhangVertexClass::kAngle);
  // the base corners are boundary vertices
  for (int v = 1; v <= 4; ++v) EXPECT_EQ(ms[v].vertex_class, ZhangVertexClass::kEdge);
}

TEST(ZhangDefinitions, CubeCornerIsAngleAndCreaseIsInnerEdge) {
  const Mesh m = gridCube(4);
  std::vector<ZhangVertexMeasures> ms;
  ASSERT_TRUE(computeZhangMeasures(m, ZhangParams{}, ms).ok());
  size_t corners = 0, creases = 0, flats = 0;
  for (size_t v = 0; v < m.vertexCount(); ++v) {
    const glm::vec3 p = m.positions[v];
    const int on_faces = (std::fabs(std::fabs(p.x) - 1) < 1e-6f) + (std::fabs(std::fabs(p.y) - 1) < 1e-6f) +
                         (std::fabs(std::fabs(p.z) - 1) < 1e-6f);
    EXPECT_EQ(ms[v].characteristic, 0u) << "closed mesh";
    if (on_faces == 3) {
      ++corners;
      EXPECT_EQ(ms[v].vertex_class, ZhangVertexClass::kAngle) << "corner " << v;
      EXPECT_GT(ms[v].super_height, 0.0f);
    } else if (on_faces == 2) {
      ++creases;
      EXPECT_EQ(ms[v].vertex_class, ZhangVertexClass::kInnerEdge) << "crease vertex " << v;
      EXPECT_NEAR(ms[v].super_height, 0.0f, 1e-6f);
    } else {
      ++flats;
      EXPECT_EQ(ms[v].vertex_class, ZhangVertexClass::kSimple) << "face vertex " << v;
      EXPECT_FLOAT_EQ(ms[v].vision, 0.0f);
    }
  }
  EXPECT_EQ(corners, 8u);
  EXPECT_EQ(creases, 12u * 3u);
  EXPECT_EQ(flats, 6u * 9u);
}

TEST(ZhangDefinitions, NonManifoldEdgeMakesComplexVertices) {
  // three triangles on the edge 0-1
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, {0.5f, -1, 0}, {0.5f, 0, 1}};
  m.triangles = {0, 1, 2, 1, 0, 3, 0, 1, 4};
  std::vector<ZhangVertexMeasures> ms;
  ASSERT_TRUE(computeZhangMeasures(m, ZhangParams{}, ms).ok());
  EXPECT_GT(ms[0].characteristic, 2u);
  EXPECT_EQ(ms[0].vertex_class, ZhangVertexClass::kComplex);
  EXPECT_EQ(ms[1].vertex_class, ZhangVertexClass::kComplex);
}

TEST(ZhangDefinitions, BadInputIsAClearError) {
  Mesh m = flatGrid(2);
  m.positions[3].x = std::numeric_limits<float>::quiet_NaN();
  std::vector<ZhangVertexMeasures> ms;
  const Error e = computeZhangMeasures(m, ZhangParams{}, ms);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("vertex 3"), std::string::npos) << e.message;
}

TEST(ZhangEdgeCollapse, SphereReachesTargetClosedAndOutward) {
  const Mesh in = icosphere(4);  // 5120 triangles
  for (size_t target : {2560u, 512u, 128u}) {
    Mesh out;
    ZhangStats st;
    ASSERT_TRUE(simplifyZhang(in, target, ZhangParams{}, out, &st).ok());
    EXPECT_EQ(st.stop_reason, ZhangStopReason::kTargetReached);
    EXPECT_LE(out.triangleCount(), target);
    EXPECT_GE(out.triangleCount(), target - 2);  // an edge collapse removes two triangles
    EXPECT_EQ(st.output_triangles, out.triangleCount());
    expectValid(out);
    expectClosedManifold(out);
    EXPECT_EQ(eulerCharacteristic(out), 2);
    // the original's local orientation is outward: no remaining triangle faces inwards
    for (size_t t = 0; t < out.triangleCount(); ++t) {
      const glm::vec3 c = (out.positions[out.triangles[3 * t]] + out.positions[out.triangles[3 * t + 1]] +
                           out.positions[out.triangles[3 * t + 2]]) / 3.0f;
      EXPECT_GT(glm::dot(glm::normalize(faceNormal(out, t)), glm::normalize(c)), 0.5f) << "triangle " << t << " target " << target;
    }
    // vertices stay near the unit sphere: displacement is measured and bounded by the shape
    EXPECT_GT(st.max_displacement, 0.0f);
    for (const glm::vec3& p : out.positions) EXPECT_NEAR(glm::length(p), 1.0f, 0.25f);
  }
}

TEST(ZhangEdgeCollapse, MergedVertexOnlyScoringAlsoKeepsSphereClosed) {
  const Mesh in = icosphere(4);
  ZhangParams narrow;
  narrow.ring_vision = false;
  Mesh with_ring, merged_only;
  ASSERT_TRUE(simplifyZhang(in, 512, ZhangParams{}, with_ring).ok());
  ASSERT_TRUE(simplifyZhang(in, 512, narrow, merged_only).ok());
  EXPECT_LE(merged_only.triangleCount(), 512u);
  EXPECT_GE(merged_only.triangleCount(), 510u);
  expectValid(merged_only);
  expectClosedManifold(merged_only);
  EXPECT_EQ(eulerCharacteristic(merged_only), 2);
  // the ring vertices' CA changes which neighbour wins, so the two scorings give different meshes
  EXPECT_NE(with_ring.positions, merged_only.positions);
}

TEST(ZhangEdgeCollapse, TorusKeepsItsGenus) {
  const Mesh in = torus(48, 24);  // 2304 triangles
  Mesh out;
  ASSERT_TRUE(simplifyZhang(in, 460, ZhangParams{}, out).ok());
  EXPECT_LE(out.triangleCount(), 460u);
  expectValid(out);
  expectClosedManifold(out);
  EXPECT_EQ(eulerCharacteristic(out), 0);
}

TEST(ZhangEdgeCollapse, CubeKeepsCornersWhenAngleVerticesAreKept) {
  const Mesh in = gridCube(6);  // 432 triangles
  ZhangParams p;
  p.keep_angle_vertices = true;
  Mesh out;
  ZhangStats st;
  ASSERT_TRUE(simplifyZhang(in, 12, p, out, &st).ok());
  expectValid(out);
  expectClosedManifold(out);
  size_t corners = 0;
  for (const glm::vec3& q : out.positions)
    if (std::fabs(std::fabs(q.x) - 1) < 1e-6f && std::fabs(std::fabs(q.y) - 1) < 1e-6f &&
        std::fabs(std::fabs(q.z) - 1) < 1e-6f)
      ++corners;
  EXPECT_EQ(corners, 8u);
  // every remaining vertex lies on the cube's surface: flat faces and creases collapse along themselves
  for (const glm::vec3& q : out.positions) {
    const float m = std::max({std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
    EXPECT_NEAR(m, 1.0f, 1e-5f);
  }
  EXPECT_LT(out.triangleCount(), 60u) << "most of the flat faces should have gone";
}

TEST(ZhangEdgeCollapse, BoundaryIsKeptAndStopIsReported) {
  const Mesh in = flatGrid(8);  // 128 triangles, 32 boundary vertices
  Mesh out;
  ZhangStats st;
  ASSERT_TRUE(simplifyZhang(in, 0, ZhangParams{}, out, &st).ok());
  EXPECT_EQ(st.stop_reason, ZhangStopReason::kNoValidCollapse);
  expectValid(out);
  // all boundary vertices are still there, unmoved, and every interior vertex is gone
  size_t boundary = 0;
  for (const glm::vec3& q : out.positions) {
    const bool on_border = q.x == 0.0f || q.y == 0.0f || q.x == 8.0f || q.y == 8.0f;
    EXPECT_TRUE(on_border) << q.x << "," << q.y;
    EXPECT_EQ(q.z, 0.0f);
    boundary += on_border;
  }
  EXPECT_EQ(boundary, 32u);
  for (size_t t = 0; t < out.triangleCount(); ++t) EXPECT_GT(faceNormal(out, t).z, 0.0f);
  // a triangulated 32-gon: 30 triangles
  EXPECT_EQ(out.triangleCount(), 30u);
  // the stop is explained by the counts: 32 kept border vertices, none movable left
  EXPECT_EQ(st.kept_edge_vertices, 32u);
  EXPECT_EQ(st.kept_complex_vertices, 0u);
  EXPECT_EQ(st.kept_angle_vertices, 0u);
  EXPECT_EQ(st.free_vertices_left, 0u);
}

TEST(ZhangEdgeCollapse, ColoursAreConvexCombinations) {
  Mesh in = icosphere(3);
  for (const glm::vec3& p : in.positions) in.colors.push_back(p.z > 0 ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1));
  Mesh out;
  ASSERT_TRUE(simplifyZhang(in, 200, ZhangParams{}, out).ok());
  ASSERT_EQ(out.colors.size(), out.vertexCount());
  for (const glm::vec3& c : out.colors) {
    EXPECT_NEAR(c.x + c.z, 1.0f, 1e-5f);
    EXPECT_NEAR(c.y, 0.0f, 1e-6f);
    EXPECT_GE(c.x, -1e-6f);
    EXPECT_GE(c.z, -1e-6f);
  }
  // the top stays mostly red and the bottom mostly blue
  for (size_t v = 0; v < out.vertexCount(); ++v) {
    if (out.positions[v].z > 0.5f) {
      EXPECT_GT(out.colors[v].x, 0.5f);
    }
    if (out.positions[v].z < -0.5f) {
      EXPECT_GT(out.colors[v].z, 0.5f);
    }
  }
}

TEST(ZhangEdgeCollapse, MultiTargetRunEqualsSeparateRuns) {
  const Mesh in = icosphere(3);  // 1280
  const std::vector<size_t> targets = {900, 400, 100};
  std::vector<Mesh> multi;
  ASSERT_TRUE(simplifyZhangMulti(in, targets, ZhangParams{}, multi).ok());
  ASSERT_EQ(multi.size(), targets.size());
  for (size_t i = 0; i < targets.size(); ++i) {
    Mesh single;
    ASSERT_TRUE(simplifyZhang(in, targets[i], ZhangParams{}, single).ok());
    EXPECT_EQ(single.triangles, multi[i].triangles) << "target " << targets[i];
    ASSERT_EQ(single.positions.size(), multi[i].positions.size());
    for (size_t v = 0; v < single.positions.size(); ++v) EXPECT_EQ(single.positions[v], multi[i].positions[v]);
  }
  EXPECT_EQ(simplifyZhangMulti(in, {100, 400}, ZhangParams{}, multi).status, Status::kInvalidArgument);
}

TEST(ZhangEdgeCollapse, SuperHeightInfluenceAlsoWorks) {
  const Mesh in = icosphere(3);
  ZhangParams p;
  p.influence = ZhangInfluence::kSuperHeight;
  Mesh out;
  ASSERT_TRUE(simplifyZhang(in, 256, p, out).ok());
  EXPECT_LE(out.triangleCount(), 256u);
  expectValid(out);
  expectClosedManifold(out);
}

TEST(ZhangTriangleDecimation, SphereReachesTargetClosed) {
  const Mesh in = icosphere(4);
  ZhangParams p;
  p.mode = ZhangMode::kTriangleDecimation;
  Mesh out;
  ZhangStats st;
  ASSERT_TRUE(simplifyZhang(in, 1024, p, out, &st).ok());
  EXPECT_EQ(st.stop_reason, ZhangStopReason::kTargetReached);
  EXPECT_LE(out.triangleCount(), 1024u);
  EXPECT_GE(out.triangleCount(), 1024u - 6u);  // a contraction removes about four triangles
  expectValid(out);
  expectClosedManifold(out);
  EXPECT_EQ(eulerCharacteristic(out), 2);
  for (size_t t = 0; t < out.triangleCount(); ++t) {
    const glm::vec3 c = out.positions[out.triangles[3 * t]];
    EXPECT_GT(glm::dot(faceNormal(out, t), c), 0.0f);
  }
}

TEST(ZhangBadInput, NonManifoldEdgeIsKeptAndResultValid) {
  Mesh in = flatGrid(6);
  const uint32_t apex = static_cast<uint32_t>(in.positions.size());
  in.positions.push_back({3.5f, 3.5f, 1.0f});
  const uint32_t a = 3 * 7 + 3, c = a + 8;  // the diagonal of an interior quad: now on 3 triangles
  in.triangles.insert(in.triangles.end(), {a, c, apex});
  std::vector<ZhangVertexMeasures> ms;
  ASSERT_TRUE(computeZhangMeasures(in, ZhangParams{}, ms).ok());
  EXPECT_EQ(ms[a].vertex_class, ZhangVertexClass::kComplex);
  EXPECT_EQ(ms[c].vertex_class, ZhangVertexClass::kComplex);
  Mesh out;
  ZhangStats st;
  ASSERT_TRUE(simplifyZhang(in, 10, ZhangParams{}, out, &st).ok());
  expectValid(out);
  EXPECT_LT(out.triangleCount(), in.triangleCount());
  // the fin's apex (an edge vertex) and the two complex vertices it stands on stay where they were
  size_t found = 0;
  for (const glm::vec3& q : out.positions)
    found += q == in.positions[apex] || q == in.positions[a] || q == in.positions[c];
  EXPECT_EQ(found, 3u);
}

TEST(ZhangBadInput, IsolatedVerticesAreDropped) {
  Mesh in = icosphere(2);
  const size_t original_vertices = in.positions.size();
  in.positions.push_back({100.0f, 100.0f, 100.0f});
  in.positions.insert(in.positions.begin() + 0, glm::vec3(-50.0f));  // shift every index by one
  for (uint32_t& i : in.triangles) ++i;
  Mesh out;
  ASSERT_TRUE(simplifyZhang(in, 100, ZhangParams{}, out).ok());
  expectValid(out);
  expectClosedManifold(out);
  EXPECT_LT(out.vertexCount(), original_vertices);
  for (const glm::vec3& q : out.positions) EXPECT_LT(glm::length(q), 1.5f) << "an isolated vertex survived";
}

TEST(ZhangBadInput, DuplicateAndDegenerateTrianglesAreDropped) {
  Mesh in = icosphere(2);  // 320 triangles
  const std::vector<uint32_t> first(in.triangles.begin(), in.triangles.begin() + 6);
  in.triangles.insert(in.triangles.end(), first.begin(), first.begin() + 3);           // same orientation
  in.triangles.insert(in.triangles.end(), {first[3], first[5], first[4]});            // reversed
  in.triangles.insert(in.triangles.end(), {first[0], first[0], first[1]});            // repeated index
  Mesh out;
  ZhangStats st;
  ASSERT_TRUE(simplifyZhang(in, 100, ZhangParams{}, out, &st).ok());
  EXPECT_EQ(st.dropped_duplicate, 2u);
  EXPECT_EQ(st.dropped_degenerate, 1u);
  EXPECT_EQ(st.input_triangles, 320u);
  EXPECT_LE(out.triangleCount(), 100u);
  expectValid(out);
  expectClosedManifold(out);  // with the duplicates removed the sphere is closed again
}

TEST(ZhangBadInput, OpenMeshWithHoleKeepsItsBorders) {
  // a sphere with a hole: the hole's rim is an edge-vertex loop and must come out unmoved
  Mesh in = icosphere(3);
  std::vector<uint32_t> kept;
  for (size_t t = 0; t < in.triangleCount(); ++t) {
    const glm::vec3 c = in.positions[in.triangles[3 * t]];
    if (c.z > 0.9f) continue;  // cut a cap off
    kept.insert(kept.end(), in.triangles.begin() + 3 * t, in.triangles.begin() + 3 * t + 3);
  }
  in.triangles = kept;
  std::vector<ZhangVertexMeasures> ms;
  ASSERT_TRUE(computeZhangMeasures(in, ZhangParams{}, ms).ok());
  std::vector<glm::vec3> rim;
  for (size_t v = 0; v < ms.size(); ++v)
    if (ms[v].vertex_class == ZhangVertexClass::kEdge) rim.push_back(in.positions[v]);
  ASSERT_GT(rim.size(), 4u);
  Mesh out;
  ASSERT_TRUE(simplifyZhang(in, in.triangleCount() / 5, ZhangParams{}, out).ok());
  expectValid(out);
  for (const glm::vec3& r : rim) {
    bool present = false;
    for (const glm::vec3& q : out.positions) present |= q == r;
    EXPECT_TRUE(present) << "rim vertex moved or lost";
  }
}

TEST(ZhangBadInput, ClearErrors) {
  Mesh in = icosphere(1);
  Mesh out;
  in.triangles[7] = 999;
  Error e = simplifyZhang(in, 10, ZhangParams{}, out);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("vertex index 999"), std::string::npos) << e.message;
  in = icosphere(1);
  in.positions[5].y = std::numeric_limits<float>::infinity();
  e = simplifyZhang(in, 10, ZhangParams{}, out);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("vertex 5"), std::string::npos) << e.message;
  ZhangParams p;
  p.max_normal_turn_deg = 0.0f;
  EXPECT_EQ(simplifyZhang(icosphere(1), 10, p, out).status, Status::kInvalidArgument);
}

TEST(ZhangBadInput, EmptyAndTinyMeshes) {
  Mesh out;
  ZhangStats st;
  EXPECT_TRUE(simplifyZhang(Mesh{}, 0, ZhangParams{}, out, &st).ok());
  EXPECT_EQ(out.triangleCount(), 0u);
  Mesh one;
  one.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  one.triangles = {0, 1, 2};
  ASSERT_TRUE(simplifyZhang(one, 0, ZhangParams{}, out, &st).ok());
  EXPECT_EQ(out.triangleCount(), 1u);  // all three vertices are boundary vertices
  EXPECT_EQ(st.stop_reason, ZhangStopReason::kNoValidCollapse);
  // a tetrahedron cannot lose an edge without becoming non-manifold
  Mesh tet;
  tet.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tet.triangles = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};
  ASSERT_TRUE(simplifyZhang(tet, 0, ZhangParams{}, out, &st).ok());
  EXPECT_EQ(out.triangleCount(), 4u);
  expectClosedManifold(out);
}

TEST(ZhangChain, LevelsHalveAndWidthsIncrease) {
  const Mesh in = icosphere(4);
  ChainParams cp;
  cp.level_count = 5;
  LodChain chain;
  ASSERT_TRUE(buildZhangChain(in, cp, chain).ok());
  ASSERT_EQ(chain.levelCount(), 6u);
  std::vector<Mesh> runs;
  std::vector<ZhangStats> stats;
  ASSERT_TRUE(simplifyZhangMulti(in, {2560, 1280, 640, 320, 160}, ZhangParams{}, runs, &stats).ok());
  EXPECT_EQ(chain.levels[0].method, LodMethod::kOriginal);
  EXPECT_EQ(chain.levels[0].mesh.triangles, in.triangles);
  for (size_t k = 1; k < chain.levelCount(); ++k) {
    const LodLevel& l = chain.levels[k];
    EXPECT_EQ(l.method, LodMethod::kZhang);
    EXPECT_LE(l.mesh.triangleCount(), in.triangleCount() >> k);
    EXPECT_GT(l.cell_width, chain.levels[k - 1].cell_width);
    EXPECT_GE(l.cell_width, zhangEquivalentCellWidth(stats[k - 1].max_surface_distance));
    EXPECT_LE(stats[k - 1].max_surface_distance, l.max_error);
    EXPECT_EQ(l.max_error, stats[k - 1].max_displacement);
    EXPECT_EQ(l.mesh.triangles, runs[k - 1].triangles);
    for (const glm::vec3& p : l.mesh.positions)
      EXPECT_LE(glm::length(p - l.bounds.center), l.bounds.radius * (1.0f + 1e-6f));
    expectClosedManifold(l.mesh);
  }
  EXPECT_NEAR(zhangEquivalentCellWidth(std::sqrt(3.0f)), 2.0f, 1e-6f);
}

TEST(ZhangEdgeCollapse, NeighbourPlacementKeepsInputPositions) {
  const Mesh in = icosphere(3);
  for (ZhangMode mode : {ZhangMode::kEdgeCollapse, ZhangMode::kTriangleDecimation}) {
    ZhangParams p;
    p.placement = ZhangPlacement::kNeighbour;
    p.mode = mode;
    Mesh out;
    ASSERT_TRUE(simplifyZhang(in, 300, p, out).ok());
    EXPECT_LE(out.triangleCount(), 300u);
    expectValid(out);
    expectClosedManifold(out);
    std::set<std::tuple<float, float, float>> original;
    for (const glm::vec3& q : in.positions) original.insert({q.x, q.y, q.z});
    for (const glm::vec3& q : out.positions) EXPECT_TRUE(original.count({q.x, q.y, q.z})) << "moved vertex";
  }
}

TEST(ZhangEdgeCollapse, BunnyToTenPercentStaysClosed) {
  SCENELOD_REQUIRE_BUNNY();
  Mesh in;
  ASSERT_TRUE(readObj(test::bunnyPath(), in).ok());
  const long chi = eulerCharacteristic(in);
  Mesh out;
  ZhangStats st;
  ASSERT_TRUE(simplifyZhang(in, in.triangleCount() / 10, ZhangParams{}, out, &st).ok());
  EXPECT_EQ(st.stop_reason, ZhangStopReason::kTargetReached);
  EXPECT_LE(out.triangleCount(), in.triangleCount() / 10);
  expectValid(out);
  expectClosedManifold(out);
  EXPECT_EQ(eulerCharacteristic(out), chi);
}

TEST(ZhangEdgeCollapse, WeldingJoinsSplitSeams) {
  // a sphere split along its seams the way glTF exports do: every triangle gets its own three vertices
  const Mesh joined = icosphere(3);
  Mesh split;
  for (uint32_t i : joined.triangles) {
    split.triangles.push_back(static_cast<uint32_t>(split.positions.size()));
    split.positions.push_back(joined.positions[i]);
    split.normals.push_back(glm::normalize(joined.positions[i]));
  }
  Mesh out;
  ZhangStats st;
  ASSERT_TRUE(simplifyZhang(split, 200, ZhangParams{}, out, &st).ok());
  EXPECT_EQ(st.collapses, 0u) << "unwelded, every vertex is a border vertex and is kept";
  EXPECT_EQ(st.stop_reason, ZhangStopReason::kNoValidCollapse);
  ZhangParams weld;
  weld.weld_positions = true;
  ASSERT_TRUE(simplifyZhang(split, 200, weld, out, &st).ok());
  EXPECT_EQ(st.stop_reason, ZhangStopReason::kTargetReached);
  EXPECT_LE(out.triangleCount(), 200u);
  expectValid(out);
  expectClosedManifold(out);
  EXPECT_EQ(eulerCharacteristic(out), 2);
  ASSERT_EQ(out.normals.size(), out.vertexCount());
  for (size_t v = 0; v < out.vertexCount(); ++v)
    EXPECT_GT(glm::dot(out.normals[v], glm::normalize(out.positions[v])), 0.8f);
}

TEST(ZhangEdgeCollapse, SurfaceDistanceIsAnUpperBound) {
  // brute force: every input vertex against every output triangle
  const Mesh in = torus(32, 16);
  Mesh out;
  ZhangStats st;
  ASSERT_TRUE(simplifyZhang(in, 150, ZhangParams{}, out, &st).ok());
  float worst = 0.0f;
  for (const glm::vec3& p : in.positions) {
    float best = INFINITY;
    for (size_t t = 0; t < out.triangleCount(); ++t) {
      // sample the triangle densely: the distance to the samples is at least the distance to it
      const glm::vec3 a = out.positions[out.triangles[3 * t]], b = out.positions[out.triangles[3 * t + 1]],
                      c = out.positions[out.triangles[3 * t + 2]];
      for (int i = 0; i <= 20; ++i)
        for (int j = 0; i + j <= 20; ++j) {
          const glm::vec3 q = a + (b - a) * (i / 20.0f) + (c - a) * (j / 20.0f);
          best = std::min(best, glm::length(p - q));
        }
    }
    worst = std::max(worst, best);
  }
  EXPECT_GT(st.max_surface_distance, 0.0f);
  EXPECT_LE(st.max_surface_distance, st.max_displacement);
  // sampled distances overestimate the true one by at most half a sample spacing (edges < 1)
  EXPECT_GE(st.max_surface_distance + 1e-6f, worst - 0.05f) << "bound " << st.max_surface_distance << " worst " << worst;
}
