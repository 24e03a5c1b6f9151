#include "scenelod/lodcore/scrooge.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "scenelod/lodcore/color_blend.h"

using namespace scenelod;

namespace {

constexpr float kPi = 3.14159265358979f;

void addFace(Mesh& m, std::initializer_list<uint32_t> corners) {
  if (m.face_offsets.empty()) m.face_offsets.push_back(0);
  m.face_corners.insert(m.face_corners.end(), corners);
  m.face_offsets.push_back(uint32_t(m.face_corners.size()));
}

// Fig. 5: the hub of a propeller, a 12-sided prism. The base is one 12-gon or, as in the paper's
// model (§7.2), 12 polygons around it (a fan from its centre here).
Mesh hub(bool fan_base) {
  Mesh m;
  const float h = 0.5f;
  for (int i = 0; i < 12; ++i) m.positions.push_back({std::cos(i * kPi / 6), std::sin(i * kPi / 6), 0.0f});
  for (int i = 0; i < 12; ++i) m.positions.push_back({std::cos(i * kPi / 6), std::sin(i * kPi / 6), h});
  if (fan_base) {
    m.positions.push_back({0, 0, 0});
    for (uint32_t i = 0; i < 12; ++i) addFace(m, {24, (i + 1) % 12, i});  // facing -z
  } else {
    m.face_offsets.push_back(0);
    for (int i = 0; i < 12; ++i) m.face_corners.push_back(uint32_t((12 - i) % 12));  // b0, b11, ..., b1
    m.face_offsets.push_back(12);
  }
  for (uint32_t i = 0; i < 12; ++i) addFace(m, {i, (i + 1) % 12, 12 + (i + 1) % 12, 12 + i});
  m.face_offsets.push_back(uint32_t(m.face_corners.size() + 12));
  for (uint32_t i = 0; i < 12; ++i) m.face_corners.push_back(12 + i);
  triangulateFaces(m);
  return m;
}

// a closed bumpy sphere of triangles, so that sub-volumes see curvature of all sizes
Mesh bumpySphere(int rings, int segments) {
  Mesh m;
  m.positions.push_back({0, 0, 1});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const float th = kPi * r / rings, ph = 2 * kPi * s / segments;
      const float rad = 1.0f + 0.04f * std::sin(5 * th) * std::sin(4 * ph);
      m.positions.push_back(rad * glm::vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  m.positions.push_back({0, 0, -1});
  const uint32_t south = uint32_t(m.positions.size() - 1);
  auto at = [&](int r, int s) { return uint32_t(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) m.triangles.insert(m.triangles.end(), {0, at(1, s), at(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.triangles.insert(m.triangles.end(), {at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      m.triangles.insert(m.triangles.end(), {at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) m.triangles.insert(m.triangles.end(), {south, at(rings - 1, s + 1), at(rings - 1, s)});
  m.colors.resize(m.positions.size());
  for (size_t v = 0; v < m.positions.size(); ++v) m.colors[v] = glm::vec3(0.5f) + 0.5f * m.positions[v];
  return m;
}

double polygonArea(const Mesh& m, size_t f) {
  glm::dvec3 n(0.0);
  const size_t b = m.face_offsets[f], e = m.face_offsets[f + 1];
  for (size_t i = b; i < e; ++i) {
    const glm::dvec3 p(m.positions[m.face_corners[i]]), q(m.positions[m.face_corners[i + 1 < e ? i + 1 : b]]);
    n += glm::cross(p, q);
  }
  return 0.5 * glm::length(n);
}

void expectValidOutput(const Mesh& out) {
  ASSERT_TRUE(validateMesh(out, "out").ok()) << validateMesh(out, "out").message;
  for (size_t t = 0; t < out.triangleCount(); ++t) {
    const uint32_t a = out.triangles[3 * t], b = out.triangles[3 * t + 1], c = out.triangles[3 * t + 2];
    EXPECT_TRUE(a != b && b != c && a != c) << "triangle " << t << " repeats a vertex";
    const float area = glm::length(glm::cross(out.positions[b] - out.positions[a], out.positions[c] - out.positions[a]));
    EXPECT_GT(area, 0.0f) << "triangle " << t << " has no area";
  }
  for (size_t f = 0; f < out.faceCount(); ++f) EXPECT_GE(out.face_offsets[f + 1] - out.face_offsets[f], 3u);
}

// closed cell containment along one axis, written independently of the implementation
bool insideCell(double a, double b, double s) {
  const double k = std::floor(a / s);
  return b <= (k + 1) * s || a == b;
}

}  // namespace

TEST(Scrooge, TwelveSidedHubBaseBecomesHexagon) {
  for (bool fan : {false, true}) {
    const Mesh in = hub(fan);
    ScroogeParams p;
    p.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(in), 1);  // the whole object (Fig. 8d)
    Mesh out;
    ScroogeStats st;
    ASSERT_TRUE(scroogeMesh(in, p, out, &st, "hub").ok());
    expectValidOutput(out);
    size_t base_faces = 0;
    for (size_t f = 0; f < out.faceCount(); ++f) {
      bool on_base = true;
      for (size_t c = out.face_offsets[f]; c < out.face_offsets[f + 1]; ++c)
        on_base = on_base && out.positions[out.face_corners[c]].z == 0.0f;
      if (!on_base) continue;
      ++base_faces;
      EXPECT_EQ(out.face_offsets[f + 1] - out.face_offsets[f], 6u) << (fan ? "fan base" : "12-gon base");
      // a regular hexagon on every other corner of the 12-gon: area 3 sqrt(3) / 2
      EXPECT_NEAR(polygonArea(out, f), 1.5 * std::sqrt(3.0), 1e-4);
    }
    EXPECT_EQ(base_faces, 1u) << (fan ? "fan base" : "12-gon base");
    EXPECT_GT(st.moved_vertices, 0u);
  }
}

TEST(Scrooge, NoVertexMovesFartherThanTheSubvolumeDiagonal) {
  const Mesh in = bumpySphere(24, 48);
  const Aabb box = computeBounds(in);
  for (int divisions : {4, 2, 1}) {
    ScroogeParams p;
    p.subvolume_size = scroogeSubvolumeForDivisions(box, divisions);
    const double l_max = glm::length(glm::dvec3(p.subvolume_size));
    Mesh out;
    ScroogeStats st;
    ASSERT_TRUE(scroogeMesh(in, p, out, &st).ok());
    expectValidOutput(out);
    ASSERT_EQ(st.vertex_origin.size(), out.vertexCount());
    EXPECT_GT(st.moved_vertices, 0u) << "nothing was degraded at 1/" << divisions * divisions * divisions;
    EXPECT_LT(out.triangleCount(), in.triangleCount());
    double worst = 0.0;
    for (size_t v = 0; v < out.vertexCount(); ++v)
      worst = std::max(worst, glm::length(glm::dvec3(out.positions[v]) - glm::dvec3(in.positions[st.vertex_origin[v]])));
    EXPECT_LE(worst, l_max * (1.0 + 1e-6)) << "divisions " << divisions;
    EXPECT_LE(double(st.max_displacement), l_max * (1.0 + 1e-6));
    EXPECT_GE(double(st.max_displacement), worst);
  }
}

TEST(Scrooge, PolygonsNeverInsideASubvolumeKeepTheirCorners) {
  // coarse spheres at 1/64 of the volume: many triangles are wider than a sub-volume
  for (auto [ring_count, segments] : {std::pair<int, int>{14, 18}, {12, 20}}) {
  SCOPED_TRACE(ring_count);
  const Mesh in = bumpySphere(ring_count, segments);
  const Aabb box = computeBounds(in);
  ScroogeParams p;
  p.subvolume_size = scroogeSubvolumeForDivisions(box, 4);
  const glm::dvec3 s(p.subvolume_size);
  Mesh out;
  ScroogeStats st;
  ASSERT_TRUE(scroogeMesh(in, p, out, &st).ok());
  EXPECT_GT(st.moved_vertices, 0u);

  // output faces as rings of positions
  std::vector<std::vector<glm::vec3>> rings;
  for (size_t f = 0; f < out.faceCount(); ++f) {
    rings.emplace_back();
    for (size_t c = out.face_offsets[f]; c < out.face_offsets[f + 1]; ++c) rings.back().push_back(out.positions[out.face_corners[c]]);
  }
  size_t outside = 0;
  for (size_t t = 0; t < in.triangleCount(); ++t) {
    const glm::vec3 a = in.positions[in.triangles[3 * t]], b = in.positions[in.triangles[3 * t + 1]],
                    c = in.positions[in.triangles[3 * t + 2]];
    const glm::dvec3 lo = glm::dvec3(glm::min(a, glm::min(b, c))), hi = glm::dvec3(glm::max(a, glm::max(b, c)));
    bool ever_inside = false;
    for (int pass = 0; pass < 8; ++pass) {
      const glm::dvec3 shift((pass & 1) ? 0.5 : 0.0, (pass & 2) ? 0.5 : 0.0, (pass & 4) ? 0.5 : 0.0);
      const glm::dvec3 o = glm::dvec3(box.min) - shift * s;
      if (insideCell(lo.x - o.x, hi.x - o.x, s.x) && insideCell(lo.y - o.y, hi.y - o.y, s.y) &&
          insideCell(lo.z - o.z, hi.z - o.z, s.z))
        ever_inside = true;
    }
    if (ever_inside) continue;
    ++outside;
    bool found = false;
    for (const auto& r : rings) {
      if (r.size() != 3) continue;
      for (int k = 0; k < 3 && !found; ++k) found = r[k] == a && r[(k + 1) % 3] == b && r[(k + 2) % 3] == c;
      if (found) break;
    }
    EXPECT_TRUE(found) << "triangle " << t << " straddles every sub-volume but changed";
  }
  EXPECT_GT(outside, 0u);  // the check above saw real cases
  }
}

TEST(Scrooge, ClosedSurfaceStaysClosed) {
  // the bumpy sphere is star-shaped about the origin: a ray from there that hits no triangle has
  // found a crack (co-linear corners and flattened polygons are only dropped once nothing moves)
  const Mesh in = bumpySphere(24, 48);
  auto hits = [](const Mesh& m, const glm::dvec3& d) {
    for (size_t t = 0; t < m.triangleCount(); ++t) {
      const glm::dvec3 a(m.positions[m.triangles[3 * t]]), b(m.positions[m.triangles[3 * t + 1]]),
          c(m.positions[m.triangles[3 * t + 2]]);
      const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
      const double det = glm::dot(e1, p);
      if (std::fabs(det) < 1e-14) continue;
      const double u = glm::dot(-a, p) / det;
      const glm::dvec3 q = glm::cross(-a, e1);
      const double v = glm::dot(d, q) / det;
      if (u >= -1e-9 && v >= -1e-9 && u + v <= 1.0 + 1e-9 && glm::dot(e2, q) / det > 0.0) return true;
    }
    return false;
  };
  for (int divisions : {2, 1}) {
    ScroogeParams p;
    p.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(in), divisions);
    Mesh out;
    ASSERT_TRUE(scroogeMesh(in, p, out).ok());
    ASSERT_LT(out.triangleCount(), in.triangleCount());
    const int n = 1000;
    int misses = 0;
    for (int i = 0; i < n; ++i) {  // a Fibonacci spiral of directions
      const double z = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - z * z), ph = 2.399963 * i;
      if (!hits(out, glm::dvec3(r * std::cos(ph), r * std::sin(ph), z))) ++misses;
    }
    EXPECT_EQ(misses, 0) << "divisions " << divisions;
  }
}

TEST(Scrooge, CoplanarNeighboursMergeWithAreaWeightedColour) {
  // a red unit square beside a blue 2 x 1 rectangle, with a colour seam at x = 1
  Mesh in;
  in.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {1, 0, 0}, {3, 0, 0}, {3, 1, 0}, {1, 1, 0}};
  in.colors = {{1, 0, 0}, {1, 0, 0}, {1, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  addFace(in, {0, 1, 2, 3});
  addFace(in, {4, 5, 6, 7});
  triangulateFaces(in);
  ScroogeParams p;
  p.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(in), 1);
  Mesh out;
  ScroogeStats st;
  ASSERT_TRUE(scroogeMesh(in, p, out, &st).ok());
  expectValidOutput(out);
  ASSERT_EQ(out.faceCount(), 1u);
  EXPECT_EQ(out.face_offsets[1], 4u);  // the co-linear seam corners are gone
  EXPECT_NEAR(polygonArea(out, 0), 3.0, 1e-6);
  EXPECT_EQ(st.merged_groups, 1u);
  for (uint32_t v : out.face_corners) {
    EXPECT_NEAR(out.colors[v].r, 1.0f / 3.0f, 1e-6f);
    EXPECT_NEAR(out.colors[v].g, 0.0f, 1e-6f);
    EXPECT_NEAR(out.colors[v].b, 2.0f / 3.0f, 1e-6f);
  }

  // the co-linear corners stay when asked to (§7.1.1)
  p.remove_colinear = false;
  ASSERT_TRUE(scroogeMesh(in, p, out).ok());
  ASSERT_EQ(out.faceCount(), 1u);
  EXPECT_EQ(out.face_offsets[1], 6u);
  expectValidOutput(out);
}

TEST(Scrooge, MergeToleranceIsMeasuredFromTheGroupsFirstPolygon) {
  // three squares in a strip, each folded up by `fold` degrees from the previous one
  auto strip = [](float fold_deg) {
    Mesh m;
    const float a = fold_deg * kPi / 180.0f;
    glm::vec3 x0(0, 0, 0), dir(1, 0, 0);
    for (int i = 0; i < 4; ++i) {
      m.positions.push_back(x0);
      m.positions.push_back(x0 + glm::vec3(0, 1, 0));
      x0 += dir;
      dir = glm::vec3(std::cos(a * (i + 1)), 0, std::sin(a * (i + 1)));
    }
    for (uint32_t i = 0; i < 3; ++i) addFace(m, {2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1});
    triangulateFaces(m);
    return m;
  };
  ScroogeParams p;
  p.theta_min_deg = 0.1f;  // no degradation: reconstruction alone
  p.theta_max_deg = 0.2f;
  for (auto [fold, expected] : {std::pair<float, size_t>{2.0f, 1}, {3.0f, 2}, {10.0f, 3}}) {
    // 2 degrees: the third square is 4 degrees from the first, inside 5; 3: it is 6 degrees away
    const Mesh in = strip(fold);
    p.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(in), 1);
    Mesh out;
    ASSERT_TRUE(scroogeMesh(in, p, out).ok());
    EXPECT_EQ(out.faceCount(), expected) << "fold " << fold;
    expectValidOutput(out);
  }
}

TEST(Scrooge, ConcaveMergedPolygonSplitsIntoConvexPieces) {
  // an L of three unit squares merges into a concave hexagon
  Mesh in;
  in.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 1, 0}, {0, 2, 0}, {1, 2, 0}};
  addFace(in, {0, 1, 4, 3});
  addFace(in, {1, 2, 5, 4});
  addFace(in, {3, 4, 7, 6});
  triangulateFaces(in);
  ScroogeParams p;
  p.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(in), 1);
  Mesh out;
  p.convex_polygons = false;
  ASSERT_TRUE(scroogeMesh(in, p, out).ok());
  ASSERT_EQ(out.faceCount(), 1u);
  EXPECT_EQ(out.face_offsets[1], 6u);
  p.convex_polygons = true;
  ASSERT_TRUE(scroogeMesh(in, p, out).ok());
  expectValidOutput(out);
  EXPECT_EQ(out.faceCount(), 2u);
  double area = 0.0;
  for (size_t f = 0; f < out.faceCount(); ++f) {
    area += polygonArea(out, f);
    const size_t b = out.face_offsets[f], k = out.face_offsets[f + 1] - b;
    for (size_t i = 0; i < k; ++i) {  // every corner turns left: convex
      const glm::vec3 a = out.positions[out.face_corners[b + i]], c = out.positions[out.face_corners[b + (i + 1) % k]],
                      d = out.positions[out.face_corners[b + (i + 2) % k]];
      EXPECT_GE(glm::cross(c - a, d - c).z, -1e-6f) << "face " << f << " is concave";
    }
  }
  EXPECT_NEAR(area, 3.0, 1e-6);
  p.triangulate_faces = true;
  ASSERT_TRUE(scroogeMesh(in, p, out).ok());
  EXPECT_EQ(out.faceCount(), out.triangleCount());
  EXPECT_EQ(out.triangleCount(), 4u);  // a hexagon needs 4 triangles
}

TEST(Scrooge, HoleInAMergedGroupIsFilledOnlyWhenAsked) {
  // a 3 x 3 grid of squares without its centre: a square ring around a hole
  Mesh in;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) in.positions.push_back({float(x), float(y), 0.0f});
  for (uint32_t y = 0; y < 3; ++y)
    for (uint32_t x = 0; x < 3; ++x)
      if (!(x == 1 && y == 1)) addFace(in, {4 * y + x, 4 * y + x + 1, 4 * (y + 1) + x + 1, 4 * (y + 1) + x});
  triangulateFaces(in);
  ScroogeParams p;
  p.theta_min_deg = 0.1f;
  p.theta_max_deg = 0.2f;
  p.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(in), 1);
  Mesh out;
  ASSERT_TRUE(scroogeMesh(in, p, out).ok());
  ASSERT_EQ(out.faceCount(), 1u);  // the paper's behaviour (§7.2): the outline only
  EXPECT_EQ(out.face_offsets[1], 4u);
  EXPECT_NEAR(polygonArea(out, 0), 9.0, 1e-6);
  p.fill_holes = false;
  p.overlap_passes = false;  // one grid: the whole ring is one group, which keeps its parts
  ASSERT_TRUE(scroogeMesh(in, p, out).ok());
  EXPECT_EQ(out.faceCount(), 8u);
  double area = 0.0;
  for (size_t f = 0; f < out.faceCount(); ++f) area += polygonArea(out, f);
  EXPECT_NEAR(area, 8.0, 1e-6);
  p.overlap_passes = true;  // shifted cells see parts of the ring without the hole and merge those
  ASSERT_TRUE(scroogeMesh(in, p, out).ok());
  EXPECT_LT(out.faceCount(), 8u);
  area = 0.0;
  for (size_t f = 0; f < out.faceCount(); ++f) area += polygonArea(out, f);
  EXPECT_NEAR(area, 8.0, 1e-6);
}

TEST(ScroogeNormalise, WeldsDuplicateVerticesExactlyOrWithinEpsilon) {
  Mesh in;
  in.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1.0000001f, 0}, {5, 5, 5}};
  in.triangles = {0, 1, 2, 3, 4, 5};  // vertex 6 is unused
  in.positions[5] = {0, 1, 0};
  Mesh out;
  ScroogeStats st;
  ScroogeParams p;
  ASSERT_TRUE(scroogeNormalise(in, p, out, &st).ok());
  EXPECT_EQ(out.vertexCount(), 4u);
  EXPECT_EQ(out.faceCount(), 2u);
  EXPECT_EQ(st.welded_vertices, 2u);

  // a vertex 1e-7 x diagonal away joins with the default epsilon (1e-6), not with 0
  in.positions[5] = {0, 1.0f, 0};
  in.positions[3] = {1e-7f * std::sqrt(75.0f), 0, 0};
  ASSERT_TRUE(scroogeNormalise(in, p, out, &st).ok());
  EXPECT_EQ(out.vertexCount(), 4u);
  p.weld_epsilon_rel = 0.0f;
  ASSERT_TRUE(scroogeNormalise(in, p, out, &st).ok());
  EXPECT_EQ(out.vertexCount(), 5u);
}

TEST(ScroogeNormalise, KeepsAttributeSeamsApart) {
  Mesh in;
  in.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  in.colors = {{1, 0, 0}, {1, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
  in.triangles = {0, 1, 2, 3, 4, 5};
  Mesh out;
  ASSERT_TRUE(scroogeNormalise(in, ScroogeParams{}, out).ok());
  EXPECT_EQ(out.vertexCount(), 6u);  // same positions, different colours: two vertices each
}

TEST(ScroogeNormalise, RemovesDuplicateAndDegeneratePolygonsButKeepsTwoSidedPairs) {
  Mesh in;
  in.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}};
  addFace(in, {0, 1, 2, 3});
  addFace(in, {2, 3, 0, 1});  // the same ring rotated: duplicate
  addFace(in, {3, 2, 1, 0});  // the back side: kept
  addFace(in, {0, 1, 4});     // co-linear: no area
  addFace(in, {0, 0, 1});     // repeated corner: two distinct corners
  triangulateFaces(in);
  Mesh out;
  ScroogeStats st;
  ASSERT_TRUE(scroogeNormalise(in, ScroogeParams{}, out, &st).ok());
  EXPECT_EQ(out.faceCount(), 2u);
  EXPECT_EQ(st.duplicate_polygons, 1u);
  EXPECT_EQ(st.degenerate_polygons, 2u);
  EXPECT_EQ(out.vertexCount(), 4u);  // vertex 4 was only used by the degenerate face
}

TEST(ScroogeNormalise, RemovesCoplanarSubPolygons) {
  Mesh in;
  in.positions = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0},          // big square
                  {1, 1, 0}, {2, 1, 0}, {2, 2, 0}, {1, 2, 0},          // inside it, same facing
                  {1, 1, 0.5f}, {2, 1, 0.5f}, {2, 2, 0.5f}, {1, 2, 0.5f},  // above it
                  {3, 3, 0}, {5, 3, 0}, {5, 5, 0}, {3, 5, 0}};         // overlapping its edge
  addFace(in, {0, 1, 2, 3});
  addFace(in, {4, 5, 6, 7});
  addFace(in, {7, 6, 5, 4});  // inside but facing the other way: kept
  addFace(in, {8, 9, 10, 11});
  addFace(in, {12, 13, 14, 15});
  triangulateFaces(in);
  Mesh out;
  ScroogeStats st;
  ScroogeParams p;
  ASSERT_TRUE(scroogeNormalise(in, p, out, &st).ok());
  EXPECT_EQ(st.sub_polygons, 1u);
  EXPECT_EQ(out.faceCount(), 4u);
  p.remove_sub_polygons = false;
  ASSERT_TRUE(scroogeNormalise(in, p, out, &st).ok());
  EXPECT_EQ(out.faceCount(), 5u);
}

TEST(ScroogeNormalise, DeduplicatesEdgesAndPoints) {
  Mesh in;
  in.positions = {{0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  in.edges = {0, 1, 2, 0, 1, 2, 1, 3};  // 0-1 twice (once via a duplicate vertex), 1-2 has no length
  in.points = {3, 3, 0};
  Mesh out;
  ASSERT_TRUE(scroogeNormalise(in, ScroogeParams{}, out).ok());
  EXPECT_EQ(out.edgeCount(), 2u);
  EXPECT_EQ(out.pointCount(), 2u);
  EXPECT_EQ(out.vertexCount(), 3u);
  EXPECT_TRUE(validateMesh(out, "out").ok());
}

TEST(Scrooge, EdgeAndPointPrimitivesPinTheirVertices) {
  Mesh in = hub(true);
  in.points = {25};  // hub(true) has vertex 24 as the base centre; add one more
  in.positions.push_back({0.5f, 0.0f, 0.0f});
  in.points = {uint32_t(in.positions.size() - 1)};
  in.edges = {13, 11};  // pins a base corner the hexagon would otherwise drop... or move
  ScroogeParams p;
  p.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(in), 1);
  Mesh out;
  ScroogeStats st;
  ASSERT_TRUE(scroogeMesh(in, p, out, &st).ok());
  expectValidOutput(out);
  ASSERT_EQ(out.edgeCount(), 1u);
  EXPECT_EQ(out.positions[out.edges[0]], in.positions[13]);
  EXPECT_EQ(out.positions[out.edges[1]], in.positions[11]);
  ASSERT_EQ(out.pointCount(), 1u);
  EXPECT_EQ(out.positions[out.points[0]], in.positions.back());
}

TEST(Scrooge, BadInputGivesClearErrors) {
  const Mesh in = hub(false);
  Mesh out;
  ScroogeParams p;
  Error e = scroogeMesh(in, p, out, nullptr, "hub.obj");  // no sub-volume size
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_NE(e.message.find("hub.obj"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("sub-volume size"), std::string::npos) << e.message;
  p.subvolume_size = glm::vec3(1.0f, std::numeric_limits<float>::quiet_NaN(), 1.0f);
  EXPECT_EQ(scroogeMesh(in, p, out).status, Status::kInvalidArgument);
  p.subvolume_size = glm::vec3(1.0f);
  p.theta_max_deg = 4.0f;  // below theta_min
  e = scroogeMesh(in, p, out);
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_NE(e.message.find("theta_min < theta_max"), std::string::npos) << e.message;
  p.theta_max_deg = 45.0f;
  p.coplanar_deg = -1.0f;
  EXPECT_EQ(scroogeMesh(in, p, out).status, Status::kInvalidArgument);
  p.coplanar_deg = 5.0f;
  p.weld_epsilon_rel = std::numeric_limits<float>::infinity();
  EXPECT_EQ(scroogeMesh(in, p, out).status, Status::kInvalidArgument);
  p.weld_epsilon_rel = 1e-6f;
  // sub-volume indices would not fit an int64 (found by the capi fuzz target)
  Mesh far = in;
  far.positions[0].x = 1e36f;
  e = scroogeMesh(far, p, out, nullptr, "hub.obj");
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_NE(e.message.find("more than 2^30 sub-volumes"), std::string::npos) << e.message;

  Mesh bad = in;
  bad.face_corners[3] = 99;
  e = scroogeMesh(bad, p, out, nullptr, "hub.obj");
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("hub.obj"), std::string::npos) << e.message;
  bad = in;
  bad.positions[0].x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(scroogeMesh(bad, p, out).status, Status::kInvalidMesh);

  ChainParams cp;
  cp.level_count = 3;
  cp.growth = 1.0f;
  LodChain chain;
  EXPECT_EQ(buildScroogeChain(in, cp, chain).status, Status::kInvalidArgument);
  cp.growth = 2.0f;
  cp.first_cell_width = -1.0f;
  EXPECT_EQ(buildScroogeChain(in, cp, chain).status, Status::kInvalidArgument);

  // an empty mesh is not an error: it gives an empty result
  EXPECT_TRUE(scroogeMesh(Mesh{}, p, out).ok());
  EXPECT_EQ(out.vertexCount(), 0u);
}

TEST(Scrooge, SubvolumeSizes) {
  Aabb box;
  box.min = {0, 0, 0};
  box.max = {4, 2, 0};
  EXPECT_EQ(scroogeSubvolumeForDivisions(box, 4), glm::vec3(1.0f, 0.5f, 1.0f));  // flat z takes the largest
  EXPECT_EQ(scroogeSubvolumeForDivisions(box, 1), glm::vec3(4.0f, 2.0f, 4.0f));
  const glm::vec3 s = scroogeSubvolumeForCellRel(box, 0.25f);
  EXPECT_NEAR(glm::length(s), 0.25f * box.diagonal(), 1e-5f);
  EXPECT_EQ(s.x, s.y);
  EXPECT_EQ(scroogeSubvolumeForCellRel(box, 0.0f), glm::vec3(0.0f));
}

TEST(Scrooge, ChainLevelsGrowAndStayWithinTheirSubvolumes) {
  const Mesh in = bumpySphere(16, 32);
  ChainParams cp;
  cp.level_count = 4;
  LodChain chain;
  ASSERT_TRUE(buildScroogeChain(in, cp, chain).ok());
  ASSERT_EQ(chain.levelCount(), 5u);
  EXPECT_EQ(chain.levels[0].mesh.triangles, in.triangles);
  EXPECT_EQ(chain.levels[0].method, LodMethod::kOriginal);
  const glm::vec3 ext = computeBounds(in).extent();
  EXPECT_NEAR(chain.levels.back().cell_width, std::max({ext.x, ext.y, ext.z}), 1e-5f);
  for (size_t k = 1; k < chain.levelCount(); ++k) {
    const LodLevel& l = chain.levels[k];
    EXPECT_EQ(l.method, LodMethod::kScrooge);
    EXPECT_GT(l.cell_width, chain.levels[k - 1].cell_width);
    EXPECT_LE(l.max_error, l.cell_width * std::sqrt(3.0f) * (1.0f + 1e-6f));
    EXPECT_LE(l.mesh.triangleCount(), in.triangleCount());
    for (const glm::vec3& v : l.mesh.positions) EXPECT_LE(glm::length(v - l.bounds.center), l.bounds.radius);
    expectValidOutput(l.mesh);
  }
  EXPECT_LT(chain.levels.back().mesh.triangleCount(), in.triangleCount());
}

TEST(Scrooge, ResultDoesNotDependOnTheRun) {
  const Mesh in = bumpySphere(16, 32);
  ScroogeParams p;
  p.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(in), 2);
  Mesh a, b;
  ASSERT_TRUE(scroogeMesh(in, p, a).ok());
  ASSERT_TRUE(scroogeMesh(in, p, b).ok());
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.face_corners, b.face_corners);
  EXPECT_EQ(a.triangles, b.triangles);
}

TEST(ColorBlend, AreaWeightedColorsWeighByBarycentricArea) {
  // two triangles of areas 1 and 3 in one group: red and blue
  Mesh m;
  m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 1, 0}, {10, 0, 0}, {13, 0, 0}, {10, 2, 0}};
  m.colors = {{1, 0, 0}, {1, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  m.triangles = {0, 1, 2, 3, 4, 5};
  std::vector<uint32_t> group = {0, 0, 0, 0, 0, 0};
  std::vector<glm::vec3> colors(2);
  group.push_back(kNoGroup);  // ignored beyond the vertex count
  areaWeightedColors(m, Span<const uint32_t>(group.data(), 6), colors);
  EXPECT_NEAR(colors[0].r, 0.25f, 1e-6f);
  EXPECT_NEAR(colors[0].b, 0.75f, 1e-6f);
  EXPECT_EQ(colors[1], glm::vec3(0.0f));  // empty group
  group = {0, 0, 0, 1, 1, kNoGroup};
  areaWeightedColors(m, Span<const uint32_t>(group.data(), 6), colors);
  EXPECT_EQ(colors[0], glm::vec3(1, 0, 0));
  EXPECT_EQ(colors[1], glm::vec3(0, 0, 1));

  const glm::vec3 p[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const glm::vec3 c[4] = {{1, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 1, 0}};
  const glm::vec3 mean = polygonMeanColor(p, c, 4);
  EXPECT_NEAR(mean.r, 0.5f, 1e-6f);  // a linear ramp over a square averages to its middle
  EXPECT_NEAR(mean.g, 0.5f, 1e-6f);
}
