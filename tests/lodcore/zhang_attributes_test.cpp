// Zhang edge collapse on meshes with texture coordinates, tangents, skins and several triangle
// groups: seams and group borders are kept (docs/ZHANG.md "Seams and attributes").
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>
#include <utility>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "scenelod/lodcore/zhang.h"

using namespace scenelod;

namespace {

// one cube face: outward axis, side, and its chart's place in a 3 x 2 atlas
struct CubeFace {
  int axis, side;
  glm::vec2 chart;
};

CubeFace cubeFace(int f) { return {f / 2, f % 2, glm::vec2(float(f % 3), float(f / 3))}; }

// the face's linear uv map: its (u, v) axes from [-1, 1] to its cell of the atlas
glm::vec2 cubeUv(const CubeFace& f, const glm::vec3& p) {
  const int ua = (f.axis + 1) % 3, va = (f.axis + 2) % 3;
  return (glm::vec2(p[ua], p[va]) * 0.5f + 0.5f + f.chart) / glm::vec2(3.0f, 2.0f);
}

// a cube of side 2 whose six faces are n x n grids with their own vertices and uv charts: every cube
// edge is a uv seam, every corner the meeting of three charts
Mesh seamedCube(int n) {
  Mesh m;
  for (int f = 0; f < 6; ++f) {
    const CubeFace face = cubeFace(f);
    const int ua = (face.axis + 1) % 3, va = (face.axis + 2) % 3;
    const uint32_t base = static_cast<uint32_t>(m.positions.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        glm::vec3 p(0.0f);
        p[face.axis] = face.side ? 1.0f : -1.0f;
        p[ua] = -1.0f + 2.0f * float(i) / float(n);
        p[va] = -1.0f + 2.0f * float(j) / float(n);
        m.positions.push_back(p);
        m.uvs.push_back(cubeUv(face, p));
        glm::vec3 nrm(0.0f);
        nrm[face.axis] = face.side ? 1.0f : -1.0f;
        m.normals.push_back(nrm);
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const uint32_t a = base + uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n) + 2, d = a + uint32_t(n) + 1;
        if (face.side) m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
        else m.triangles.insert(m.triangles.end(), {a, c, b, a, d, c});
      }
  }
  return m;
}

glm::vec3 triangleNormal(const Mesh& m, size_t t) {
  const glm::vec3 &a = m.positions[m.triangles[3 * t]], &b = m.positions[m.triangles[3 * t + 1]],
                  &c = m.positions[m.triangles[3 * t + 2]];
  return glm::normalize(glm::cross(b - a, c - a));
}

// every triangle lies on one cube face and each corner's uv is that face's chart at its position
void expectCubeCharts(const Mesh& out) {
  ASSERT_EQ(out.uvs.size(), out.positions.size());
  for (size_t t = 0; t < out.triangleCount(); ++t) {
    const glm::vec3 n = triangleNormal(out, t);
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (std::fabs(n[a]) > std::fabs(n[axis])) axis = a;
    ASSERT_GT(std::fabs(n[axis]), 0.9999f) << "triangle " << t << " leaves its cube face";
    const CubeFace face = cubeFace(2 * axis + (n[axis] > 0.0f ? 1 : 0));
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = out.triangles[3 * t + c];
      const glm::vec2 want = cubeUv(face, out.positions[v]);
      EXPECT_NEAR(out.uvs[v].x, want.x, 1e-5f) << "triangle " << t << " corner " << c;
      EXPECT_NEAR(out.uvs[v].y, want.y, 1e-5f) << "triangle " << t << " corner " << c;
    }
  }
}

// flat n x n grid over [0, 1]^2 (z = 0) with uv = (x, y); triangles left of x = 0.5 in group 0, the
// others in group 1, sharing the vertices on the border
Mesh twoMaterialPlane(int n) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const glm::vec3 p(float(i) / float(n), float(j) / float(n), 0.0f);
      m.positions.push_back(p);
      m.uvs.push_back(glm::vec2(p.x, p.y));
      m.normals.push_back(glm::vec3(0, 0, 1));
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n) + 2, d = a + uint32_t(n) + 1;
      m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
      const uint32_t group = 2 * i < n ? 0u : 1u;
      m.triangle_groups.insert(m.triangle_groups.end(), {group, group});
    }
  return m;
}

// unit sphere, `rings` x `segments` quads with a latitude-longitude uv map whose seam is the meridian
// at u = 0 = 1 (split vertices there); one vertex per pole
Mesh latLongSphere(int rings, int segments) {
  Mesh m;
  const float pi = 3.14159265f;
  m.positions.push_back({0, 0, 1});
  m.uvs.push_back({0.5f, 0.0f});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s <= segments; ++s) {
      const float th = pi * float(r) / float(rings), ph = 2.0f * pi * float(s % segments) / float(segments);
      m.positions.push_back({std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)});
      m.uvs.push_back({float(s) / float(segments), float(r) / float(rings)});
    }
  m.positions.push_back({0, 0, -1});
  m.uvs.push_back({0.5f, 1.0f});
  const uint32_t south = uint32_t(m.positions.size() - 1);
  auto at = [&](int r, int s) { return uint32_t(1 + (r - 1) * (segments + 1) + s); };
  for (int s = 0; s < segments; ++s) {
    m.triangles.insert(m.triangles.end(), {0, at(1, s), at(1, s + 1)});
    m.triangles.insert(m.triangles.end(), {south, at(rings - 1, s + 1), at(rings - 1, s)});
    for (int r = 1; r + 1 < rings; ++r)
      m.triangles.insert(m.triangles.end(), {at(r, s), at(r + 1, s), at(r + 1, s + 1), at(r, s), at(r + 1, s + 1), at(r, s + 1)});
  }
  return m;
}

size_t distinctPositions(const Mesh& m) {
  std::set<std::tuple<float, float, float>> s;
  for (const glm::vec3& p : m.positions) s.insert({p.x, p.y, p.z});
  return s.size();
}

TEST(ZhangAttributes, SeamedCubeKeepsEveryChartsUvs) {
  const Mesh cube = seamedCube(8);
  for (ZhangMode mode : {ZhangMode::kEdgeCollapse, ZhangMode::kTriangleDecimation})
    for (ZhangPlacement placement : {ZhangPlacement::kInterpolated, ZhangPlacement::kNeighbour}) {
      SCOPED_TRACE(std::string(zhangModeName(mode)) + " " + zhangPlacementName(placement));
      ZhangParams params;
      params.mode = mode;
      params.placement = placement;
      Mesh out;
      ZhangStats stats;
      ASSERT_TRUE(simplifyZhang(cube, 60, params, out, &stats).ok());
      // welded by position: the seams are not borders, so the cube is closed and reduces well
      EXPECT_EQ(stats.kept_edge_vertices, 0u);
      EXPECT_GT(stats.seam_vertices, 0u);
      // triangle contraction pins every seam vertex (at most one per triangle), so it stops earlier
      EXPECT_LE(out.triangleCount(), mode == ZhangMode::kEdgeCollapse ? 60u : cube.triangleCount() / 3);
      expectCubeCharts(out);
      // the eight corners and both uvs along every seam stay: more vertices than positions
      EXPECT_GT(out.vertexCount(), distinctPositions(out));
      ASSERT_EQ(stats.source_vertex.size(), out.vertexCount());
      for (uint32_t src : stats.source_vertex) ASSERT_LT(src, cube.vertexCount());
    }
}

TEST(ZhangAttributes, NonIndexedInputIsWeldedByItsAttributes) {
  // every triangle with its own three vertices (as the glTF Fox comes): equal vertices are one wedge,
  // so the result is the indexed cube's
  const Mesh indexed = seamedCube(8);
  Mesh loose;
  for (uint32_t v : indexed.triangles) {
    loose.triangles.push_back(uint32_t(loose.positions.size()));
    loose.positions.push_back(indexed.positions[v]);
    loose.normals.push_back(indexed.normals[v]);
    loose.uvs.push_back(indexed.uvs[v]);
  }
  Mesh a, b;
  ZhangStats sa, sb;
  ASSERT_TRUE(simplifyZhang(indexed, 60, ZhangParams{}, a, &sa).ok());
  ASSERT_TRUE(simplifyZhang(loose, 60, ZhangParams{}, b, &sb).ok());
  EXPECT_EQ(sb.seam_vertices, sa.seam_vertices);
  EXPECT_EQ(b.triangleCount(), a.triangleCount());
  EXPECT_EQ(b.vertexCount(), a.vertexCount());
  expectCubeCharts(b);
}

TEST(ZhangAttributes, SeamVerticesMoveOnlyAlongTheirSeam) {
  const Mesh cube = seamedCube(8);
  Mesh out;
  ASSERT_TRUE(simplifyZhang(cube, 60, ZhangParams{}, out).ok());
  // a vertex on a cube edge (two coordinates at +-1) never leaves the cube's edges
  auto onEdge = [](const glm::vec3& p) {
    int at_face = 0;
    for (int a = 0; a < 3; ++a) at_face += std::fabs(std::fabs(p[a]) - 1.0f) < 1e-6f;
    return at_face >= 2;
  };
  size_t edge_vertices = 0;
  for (const glm::vec3& p : out.positions) edge_vertices += onEdge(p);
  for (const glm::vec3& p : cube.positions) ASSERT_TRUE(std::fabs(p.x) <= 1.0f && std::fabs(p.y) <= 1.0f);
  // the 8 corners, each in 3 charts
  EXPECT_GE(edge_vertices, 24u);
  for (size_t t = 0; t < out.triangleCount(); ++t) {
    // no triangle spans a cube edge: its corners share one face plane
    const glm::vec3 n = triangleNormal(out, t);
    EXPECT_GT(std::max({std::fabs(n.x), std::fabs(n.y), std::fabs(n.z)}), 0.9999f);
  }
}

TEST(ZhangAttributes, NeighbourPlacementKeepsEachSourcesAttributes) {
  const Mesh cube = seamedCube(6);
  ZhangParams params;
  params.placement = ZhangPlacement::kNeighbour;
  Mesh out;
  ZhangStats stats;
  ASSERT_TRUE(simplifyZhang(cube, 40, params, out, &stats).ok());
  ASSERT_EQ(stats.source_vertex.size(), out.vertexCount());
  for (size_t v = 0; v < out.vertexCount(); ++v) {
    const uint32_t src = stats.source_vertex[v];
    EXPECT_EQ(out.positions[v], cube.positions[src]);
    EXPECT_EQ(out.uvs[v], cube.uvs[src]);
    EXPECT_EQ(out.normals[v], cube.normals[src]);
  }
}

TEST(ZhangAttributes, TwoMaterialsStaySeparate) {
  const Mesh plane = twoMaterialPlane(16);
  for (ZhangMode mode : {ZhangMode::kEdgeCollapse, ZhangMode::kTriangleDecimation}) {
    SCOPED_TRACE(zhangModeName(mode));
    ZhangParams params;
    params.mode = mode;
    Mesh out;
    ZhangStats stats;
    ASSERT_TRUE(simplifyZhang(plane, 100, params, out, &stats).ok());
    ASSERT_EQ(out.triangle_groups.size(), out.triangleCount());
    EXPECT_LT(out.triangleCount(), plane.triangleCount() / 2);
    std::set<uint32_t> groups(out.triangle_groups.begin(), out.triangle_groups.end());
    EXPECT_EQ(groups, (std::set<uint32_t>{0, 1}));
    std::vector<int> vertex_group(out.vertexCount(), -1);
    for (size_t t = 0; t < out.triangleCount(); ++t) {
      const uint32_t g = out.triangle_groups[t];
      for (int c = 0; c < 3; ++c) {
        const uint32_t v = out.triangles[3 * t + c];
        const glm::vec3& p = out.positions[v];
        // the group border x = 0.5 stays where it was: no triangle crosses it
        if (g == 0) EXPECT_LE(p.x, 0.5f + 1e-6f) << "triangle " << t;
        else EXPECT_GE(p.x, 0.5f - 1e-6f) << "triangle " << t;
        // a linear uv map stays exact, and each output vertex serves one group
        EXPECT_NEAR(out.uvs[v].x, p.x, 1e-5f);
        EXPECT_NEAR(out.uvs[v].y, p.y, 1e-5f);
        EXPECT_TRUE(vertex_group[v] == -1 || vertex_group[v] == int(g)) << "vertex " << v;
        vertex_group[v] = int(g);
      }
    }
  }
}

TEST(ZhangAttributes, MirroredTangentsKeepTheirSigns) {
  // uv mirrored at x = 0.5: the left half has tangent +x, w = +1, the right half the vertices on the
  // mirror line split with w = -1
  Mesh m = twoMaterialPlane(16);
  m.triangle_groups.clear();
  const size_t n = 16, row = n + 1;
  m.tangents.assign(m.vertexCount(), glm::vec4(1, 0, 0, 1));
  std::map<uint32_t, uint32_t> mirror;  // vertex on the mirror line -> its right-hand copy
  for (uint32_t v = 0; v < m.vertexCount(); ++v) {
    const glm::vec3 p = m.positions[v];
    if (p.x > 0.5f) m.tangents[v] = glm::vec4(-1, 0, 0, -1);
    if (p.x > 0.5f) m.uvs[v].x = 1.0f - p.x;
    if (v % row == n / 2) {
      mirror[v] = uint32_t(m.positions.size());
      m.positions.push_back(p);
      m.uvs.push_back(m.uvs[v]);
      m.normals.push_back(m.normals[v]);
      m.tangents.push_back(glm::vec4(-1, 0, 0, -1));
    }
  }
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    glm::vec3 centre(0.0f);
    for (int c = 0; c < 3; ++c) centre += m.positions[m.triangles[3 * t + c]] / 3.0f;
    if (centre.x > 0.5f)
      for (int c = 0; c < 3; ++c)
        if (mirror.count(m.triangles[3 * t + c])) m.triangles[3 * t + c] = mirror[m.triangles[3 * t + c]];
  }
  Mesh out;
  ASSERT_TRUE(simplifyZhang(m, 100, ZhangParams{}, out).ok());
  ASSERT_EQ(out.tangents.size(), out.vertexCount());
  EXPECT_LT(out.triangleCount(), m.triangleCount() / 2);
  for (size_t t = 0; t < out.triangleCount(); ++t) {
    glm::vec3 centre(0.0f);
    for (int c = 0; c < 3; ++c) centre += out.positions[out.triangles[3 * t + c]] / 3.0f;
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = out.triangles[3 * t + c];
      EXPECT_EQ(out.tangents[v].w, centre.x < 0.5f ? 1.0f : -1.0f) << "triangle " << t;
      EXPECT_NEAR(glm::length(glm::vec3(out.tangents[v])), 1.0f, 1e-5f);
      EXPECT_NEAR(glm::dot(glm::vec3(out.tangents[v]), out.normals[v]), 0.0f, 1e-5f);
      const float want_u = out.positions[v].x > 0.5f || centre.x > 0.5f ? 1.0f - out.positions[v].x : out.positions[v].x;
      EXPECT_NEAR(out.uvs[v].x, want_u, 1e-5f);
    }
  }
}

TEST(ZhangAttributes, SkinOfTheSurvivorIsCarried) {
  Mesh cube = seamedCube(6);
  cube.joints.resize(cube.vertexCount());
  cube.weights.resize(cube.vertexCount());
  for (size_t v = 0; v < cube.vertexCount(); ++v) {
    const uint16_t j = cube.positions[v].x > 0.0f ? 1 : 0;
    cube.joints[v] = glm::u16vec4(j, 2, 0, 0);
    cube.weights[v] = glm::vec4(0.75f, 0.25f, 0.0f, 0.0f);
  }
  cube.joint_parents = {-1, 0, 0};
  Mesh out;
  ZhangStats stats;
  ASSERT_TRUE(simplifyZhang(cube, 40, ZhangParams{}, out, &stats).ok());
  ASSERT_TRUE(validateMesh(out, "skinned level").ok());
  ASSERT_EQ(out.joints.size(), out.vertexCount());
  EXPECT_EQ(out.joint_parents, cube.joint_parents);
  for (size_t v = 0; v < out.vertexCount(); ++v) {
    EXPECT_EQ(out.joints[v], cube.joints[stats.source_vertex[v]]);
    EXPECT_EQ(out.weights[v], cube.weights[stats.source_vertex[v]]);
  }
}

TEST(ZhangAttributes, ChainLevelsRecordTheirSourceVertices) {
  const Mesh cube = seamedCube(8);
  ChainParams params;
  params.level_count = 4;
  LodChain chain;
  ASSERT_TRUE(buildZhangChain(cube, params, chain).ok());
  ASSERT_GE(chain.levelCount(), 3u);
  EXPECT_TRUE(chain.levels[0].source_vertex.empty());
  for (size_t l = 1; l < chain.levelCount(); ++l) {
    const LodLevel& level = chain.levels[l];
    ASSERT_EQ(level.source_vertex.size(), level.mesh.vertexCount()) << "level " << l;
    for (uint32_t src : level.source_vertex) ASSERT_LT(src, cube.vertexCount());
    expectCubeCharts(level.mesh);
  }
}

TEST(ZhangAttributes, OneGroupEverywhereIsAPlainMesh) {
  // triangle groups all equal do not switch on the seam handling: the output equals the plain one
  Mesh plain = seamedCube(5);
  plain.uvs.clear();
  Mesh grouped = plain;
  grouped.triangle_groups.assign(grouped.triangleCount(), 3u);
  Mesh a, b;
  ZhangStats sa, sb;
  ASSERT_TRUE(simplifyZhang(plain, 50, ZhangParams{}, a, &sa).ok());
  ASSERT_TRUE(simplifyZhang(grouped, 50, ZhangParams{}, b, &sb).ok());
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(sb.seam_vertices, 0u);
  EXPECT_EQ(b.triangle_groups, std::vector<uint32_t>(b.triangleCount(), 3u));
  // unwelded, its split cube edges are borders that never move
  EXPECT_GT(sa.kept_edge_vertices, 0u);
}

TEST(ZhangAttributes, SeamBendLimitsCollapsesAlongACurvedSeam) {
  // the seam meridian bends by 180 / 16 degrees at each vertex
  const Mesh sphere = latLongSphere(16, 32);
  auto seamVertices = [](const Mesh& m) {
    // positions with two uvs (u = 0 and u = 1)
    std::map<std::tuple<float, float, float>, std::set<float>> us;
    for (size_t v = 0; v < m.vertexCount(); ++v)
      us[{m.positions[v].x, m.positions[v].y, m.positions[v].z}].insert(m.uvs[v].x);
    size_t seam = 0;
    for (const auto& entry : us) seam += entry.second.size() == 2;
    return seam;
  };
  ASSERT_EQ(seamVertices(sphere), 15u);
  ZhangParams straight;
  straight.max_seam_bend_deg = 5.0f;
  Mesh kept, reduced;
  ASSERT_TRUE(simplifyZhang(sphere, 200, straight, kept).ok());
  EXPECT_EQ(seamVertices(kept), 15u);
  ASSERT_TRUE(simplifyZhang(sphere, 200, ZhangParams{}, reduced).ok());
  EXPECT_LT(seamVertices(reduced), 15u);
  EXPECT_GT(seamVertices(reduced), 0u);
  // every corner keeps its side's u: a triangle's u values span less than half the map
  for (const Mesh* m : {&kept, &reduced})
    for (size_t t = 0; t < m->triangleCount(); ++t) {
      float lo = 1.0f, hi = 0.0f;
      for (int c = 0; c < 3; ++c) {
        const glm::vec2 uv = m->uvs[m->triangles[3 * t + c]];
        if (uv.y == 0.0f || uv.y == 1.0f) continue;  // a pole
        lo = std::min(lo, uv.x);
        hi = std::max(hi, uv.x);
      }
      EXPECT_LT(hi - lo, 0.5f) << "triangle " << t;
    }
}

TEST(ZhangAttributes, BadAttributesAreClearErrors) {
  Mesh m = seamedCube(2);
  m.uvs[5].x = std::nanf("");
  Mesh out;
  Error e = simplifyZhang(m, 4, ZhangParams{}, out);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("texture coordinates"), std::string::npos) << e.message;
  m = seamedCube(2);
  m.triangle_groups.assign(m.triangleCount() - 1, 0u);
  e = simplifyZhang(m, 4, ZhangParams{}, out);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("triangle groups"), std::string::npos) << e.message;
  ChainParams params;
  LodChain chain;
  e = buildZhangChain(m, params, chain);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_TRUE(chain.empty());
}

TEST(ZhangAttributes, BadSeamBendIsRefused) {
  ZhangParams params;
  params.max_seam_bend_deg = -1.0f;
  Mesh out;
  const Error e = simplifyZhang(seamedCube(2), 4, params, out);
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_NE(e.message.find("max_seam_bend_deg"), std::string::npos) << e.message;
}

}  // namespace
