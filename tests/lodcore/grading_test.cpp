// Grading (Low & Tan 1997 §3.1; Rossignac & Borrel 1993) on constructed vertices.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/obj_io.h"
#include "test_hooks.h"
#include "test_support.h"
#include "scenelod/lodcore/cluster.h"

using namespace scenelod;

namespace {

// a square pyramid with apex 4 at height h over the square (+-1, +-1, 0), base closed by 2 triangles
Mesh pyramid(float h) {
  Mesh m;
  m.positions = {{1, 1, 0}, {-1, 1, 0}, {-1, -1, 0}, {1, -1, 0}, {0, 0, h}};
  m.triangles = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4, 0, 2, 1, 0, 3, 2};
  return m;
}

}  // namespace

TEST(Grading, FlatInteriorVertexHasZeroAngularFactorAndWeight) {
  // theta = pi for a vertex inside a plane (opposite incident edges), so cos(theta/2) = 0: a flat
  // vertex is never on a silhouette and weighs nothing, with or without the feature boost
  const Mesh grid = test::makeGrid(4, 4.0f);
  const uint32_t centre = 2 * 5 + 2;
  for (bool boost : {false, true}) {
    std::vector<float> w, ang;
    gradeVertices(grid, Grading::kLowTan, boost, w, &ang);
    EXPECT_NEAR(ang[centre], 0.0f, 1e-4f);
    EXPECT_NEAR(w[centre], 0.0f, 1e-4f);
  }
}

TEST(Grading, CubeCornerIsCosineOfHalfRightAngle) {
  // every incident edge of the box's min corner points into the positive octant, the widest pair is
  // 90 degrees apart: cos(45 deg); the corner also has the mesh's longest edge (a face diagonal)
  const Mesh box = test::makeBox({0, 0, 0}, {1, 1, 1}, 1);
  std::vector<float> w, ang;
  float longest = 0.0f;
  gradeVertices(box, Grading::kLowTan, false, w, &ang, &longest);
  EXPECT_NEAR(longest, std::sqrt(2.0f), 1e-5f);
  EXPECT_NEAR(ang[0], std::cos(3.14159265f / 4.0f), 1e-5f);
  EXPECT_NEAR(w[0], std::cos(3.14159265f / 4.0f), 1e-5f);  // longest incident edge / longest edge = 1
}

TEST(Grading, SharpApexApproachesOneAndMatchesFormula) {
  for (float h : {0.5f, 3.0f, 20.0f}) {
    const Mesh m = pyramid(h);
    std::vector<float> w, ang;
    float longest = 0.0f;
    gradeVertices(m, Grading::kLowTan, false, w, &ang, &longest);
    // widest pair at the apex: edges to opposite base corners (1,1,-h) and (-1,-1,-h)
    const float cos_theta = (h * h - 2.0f) / (h * h + 2.0f);
    const float theta = std::acos(cos_theta);
    EXPECT_NEAR(ang[4], std::cos(theta / 2.0f), 1e-5f) << "h = " << h;
    EXPECT_NEAR(w[4], ang[4] * std::sqrt(2.0f + h * h) / longest, 1e-5f);
    std::vector<float> wr, angr;
    gradeVertices(m, Grading::kRossignac, false, wr, &angr);
    EXPECT_NEAR(angr[4], 3.14159265f / theta, 1e-3f) << "h = " << h;
  }
  // the sharper the apex, the heavier under cos(theta/2), bounded by 1
  std::vector<float> a, b, ang_a, ang_b;
  gradeVertices(pyramid(0.5f), Grading::kLowTan, false, a, &ang_a);
  gradeVertices(pyramid(20.0f), Grading::kLowTan, false, b, &ang_b);
  EXPECT_LT(ang_a[4], ang_b[4]);
  EXPECT_LE(ang_b[4], 1.0f);
}

TEST(Grading, BoostRaisesBoundaryAndCreaseVertices) {
  // a vertex in the middle of a grid's border: theta = pi, so 0 without the boost, 0.5 with it
  const Mesh grid = test::makeGrid(4, 4.0f);
  const uint32_t border = 2;  // (2, 0)
  std::vector<float> w, ang;
  gradeVertices(grid, Grading::kLowTan, false, w, &ang);
  EXPECT_NEAR(ang[border], 0.0f, 1e-4f);
  gradeVertices(grid, Grading::kLowTan, true, w, &ang);
  EXPECT_NEAR(ang[border], 0.5f, 1e-5f);
  // a vertex in the middle of a box edge: theta = pi, dihedral 90 degrees: (1 - cos 90)/2 = 0.5
  const Mesh box = test::makeBox({0, 0, 0}, {2, 2, 2}, 2);
  const uint32_t mid_edge = 1;  // on face z = 0, at (0, 1, 0)
  ASSERT_NEAR(box.positions[mid_edge].y, 1.0f, 1e-6f);
  ASSERT_NEAR(box.positions[mid_edge].x, 0.0f, 1e-6f);
  gradeVertices(box, Grading::kLowTan, false, w, &ang);
  EXPECT_NEAR(ang[mid_edge], 0.0f, 1e-4f);
  gradeVertices(box, Grading::kLowTan, true, w, &ang);
  EXPECT_NEAR(ang[mid_edge], 0.5f, 1e-4f);
}

TEST(Grading, PreparedOrderIsHeaviestFirstAndSkipsUnreferencedVertices) {
  Mesh m = test::makeSphere({0, 0, 0}, 1.0f, 8, 12);
  m.positions.push_back({5, 5, 5});  // referenced by nothing
  PreparedMesh p;
  ASSERT_TRUE(prepareMesh(m, ClusterParams(), p).ok());
  EXPECT_EQ(p.order.size(), m.positions.size() - 1);
  for (size_t i = 1; i < p.order.size(); ++i) {
    EXPECT_GE(p.weights[p.order[i - 1]], p.weights[p.order[i]]);
    if (p.weights[p.order[i - 1]] == p.weights[p.order[i]]) {
      EXPECT_LT(p.order[i - 1], p.order[i]);
    }
  }
  EXPECT_LE(p.bounds.max.x, 1.0f + 1e-6f);  // the unreferenced vertex is not in the bounds
}

TEST(Grading, ZeroLengthEdgesGiveFiniteWeights) {
  Mesh m;
  m.positions = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {0, 1, 2, 0, 3, 4};
  std::vector<float> w;
  gradeVertices(m, Grading::kLowTan, true, w);
  for (float x : w) EXPECT_TRUE(std::isfinite(x) && x >= 0.0f);
  EXPECT_EQ(w[1], 0.0f);  // only zero-length edges
}

TEST(Grading, LongFanIsGradedLikeAShortOne) {
  // a flat fan of n triangles around vertex 0: past 64 incidences the distinct neighbours are found
  // by sorting instead of scanning; either way the closed fan's centre is a flat interior vertex
  // (0), and with one triangle removed it is a boundary vertex (0.5 with the boost)
  for (int n : {8, 100}) {
    Mesh m;
    m.positions.push_back({0, 0, 0});
    for (int i = 0; i < n; ++i) {
      const float a = 2.0f * 3.14159265f * float(i) / float(n);
      m.positions.push_back({std::cos(a), std::sin(a), 0.0f});
    }
    for (int i = 0; i < n; ++i) m.triangles.insert(m.triangles.end(), {0u, uint32_t(1 + i), uint32_t(1 + (i + 1) % n)});
    std::vector<float> w, ang;
    gradeVertices(m, Grading::kLowTan, true, w, &ang);
    EXPECT_NEAR(ang[0], 0.0f, 1e-4f) << n;
    m.triangles.resize(m.triangles.size() - 3);
    gradeVertices(m, Grading::kLowTan, true, w, &ang);
    EXPECT_NEAR(ang[0], 0.5f, 1e-5f) << n;
  }
}

TEST(Grading, PreparedBoundsAndOrderIncludePointOnlyVertices) {
  Mesh m = test::makeSphere({0, 0, 0}, 1.0f, 8, 12);
  m.positions.push_back({5, -6, 7});
  m.points.push_back(uint32_t(m.positions.size() - 1));
  PreparedMesh p;
  ASSERT_TRUE(prepareMesh(m, ClusterParams(), p).ok());
  EXPECT_EQ(p.order.size(), m.positions.size());
  EXPECT_EQ(p.bounds.max.x, 5.0f);
  EXPECT_EQ(p.bounds.min.y, -6.0f);
  EXPECT_EQ(p.bounds.max.z, 7.0f);
  EXPECT_NEAR(p.bounds.min.x, -1.0f, 1e-5f);
}

TEST(Grading, PreparedMeshDoesNotDependOnColours) {
  // colours only add face_colors; a mesh with them is graded by the one-incidence-at-a-time pass,
  // one without by the four-lane pass (rows of up to 16 triangle corners): weights, order and face
  // sums must agree bit for bit, also on degenerate input (repeated and zero-area triangles,
  // coincident vertices, non-manifold fans, rows longer than 16)
  std::vector<Mesh> meshes = {test::makeSphere({0, 0, 0}, 1.0f, 9, 14), test::makeCadPart()};
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    std::mt19937 rng(seed);
    Mesh m;
    const uint32_t vn = 4 + rng() % 60;
    for (uint32_t i = 0; i < vn; ++i) {
      if (i > 0 && rng() % 8 == 0) {
        m.positions.push_back(m.positions[rng() % i]);  // coincident
      } else if (seed % 2) {
        m.positions.push_back({float(rng() % 5), float(rng() % 5), float(rng() % 3)});  // exact zeros
      } else {
        auto unit = [&] { return float(rng() % 1000) / 999.0f; };
        m.positions.push_back({unit(), unit(), unit()});
      }
    }
    const uint32_t tn = 1 + rng() % (4 * vn), window = 2 + rng() % vn;
    for (uint32_t t = 0; t < tn; ++t) {
      const uint32_t base = rng() % vn;
      for (int k = 0; k < 3; ++k) m.triangles.push_back((base + rng() % window) % vn);
    }
    meshes.push_back(m);
  }
  for (size_t i = 0; i < meshes.size(); ++i) {
    Mesh plain = meshes[i], coloured = meshes[i];
    coloured.colors.assign(coloured.positions.size(), glm::vec3(0.25f, 0.5f, 0.75f));
    for (Grading g : {Grading::kLowTan, Grading::kRossignac})
      for (bool boost : {true, false}) {
        ClusterParams params;
        params.grading = g;
        params.boost_features = boost;
        PreparedMesh a, b;
        ASSERT_TRUE(prepareMesh(plain, params, a).ok());
        ASSERT_TRUE(prepareMesh(coloured, params, b).ok());
        ASSERT_EQ(a.weights.size(), b.weights.size());
        for (size_t v = 0; v < a.weights.size(); ++v) {
          ASSERT_EQ(std::memcmp(&a.weights[v], &b.weights[v], sizeof(float)), 0) << "mesh " << i << " vertex " << v;
          ASSERT_EQ(std::memcmp(&a.face_sums[v].area, &b.face_sums[v].area, sizeof(float)), 0) << i << " " << v;
          for (int k = 0; k < 9; ++k) ASSERT_EQ(a.face_sums[v].q[k], b.face_sums[v].q[k]) << i << " " << v << " " << k;
        }
        EXPECT_EQ(a.order, b.order) << i;
        EXPECT_EQ(a.longest_edge, b.longest_edge) << i;
        EXPECT_EQ(a.surface_area, b.surface_area) << i;
      }
  }
}

namespace {

// the vertices renumbered at random (triangles, edges and points remapped), and with `collapse`,
// every collapse-th vertex moved onto another's position (zero-length edges, zero-area faces)
Mesh shuffledVertices(const Mesh& in, uint32_t seed, size_t collapse) {
  const size_t vn = in.vertexCount();
  std::vector<uint32_t> to(vn);
  for (size_t v = 0; v < vn; ++v) to[v] = static_cast<uint32_t>(v);
  std::mt19937 rng(seed);
  std::shuffle(to.begin(), to.end(), rng);
  Mesh m = in;
  for (size_t v = 0; v < vn; ++v) m.positions[to[v]] = in.positions[v];
  if (!in.colors.empty())
    for (size_t v = 0; v < vn; ++v) m.colors[to[v]] = in.colors[v];
  for (uint32_t& i : m.triangles) i = to[i];
  for (uint32_t& i : m.edges) i = to[i];
  for (uint32_t& i : m.points) i = to[i];
  if (collapse)
    for (size_t v = collapse; v < vn; v += collapse) m.positions[v] = m.positions[v - 1];
  return m;
}

// prepareMesh with the AVX2 paths and with the baseline give the same weights, face sums, order, sorted positions and
// longest edge, under both gradings, with and without the boost
void expectAvx2GivesTheBaselineBits(const Mesh& mesh, const std::string& label) {
  detail::HookGuard avx2(detail::useAvx2Paths, true);
  for (Grading g : {Grading::kLowTan, Grading::kRossignac})
    for (bool boost : {true, false}) {
      ClusterParams params;
      params.grading = g;
      params.boost_features = boost;
      PreparedMesh wide, base;
      avx2.set(true);
      ASSERT_TRUE(prepareMesh(mesh, params, wide).ok());
      avx2.set(false);
      ASSERT_TRUE(prepareMesh(mesh, params, base).ok());
      SCOPED_TRACE(label + " " + gradingName(g) + (boost ? " boost" : ""));
      ASSERT_EQ(wide.weights.size(), base.weights.size());
      ASSERT_EQ(wide.face_sums.size(), base.face_sums.size());
      EXPECT_EQ(std::memcmp(wide.weights.data(), base.weights.data(), base.weights.size() * sizeof(float)), 0);
      for (size_t v = 0; v < base.face_sums.size(); ++v) {
        ASSERT_EQ(std::memcmp(&wide.face_sums[v].area, &base.face_sums[v].area, sizeof(float)), 0) << v;
        for (int k = 0; k < 9; ++k) ASSERT_EQ(wide.face_sums[v].q[k], base.face_sums[v].q[k]) << v << " " << k;
      }
      EXPECT_EQ(wide.order, base.order);
      ASSERT_EQ(wide.sorted_positions.size(), base.sorted_positions.size());
      EXPECT_EQ(std::memcmp(wide.sorted_positions.data(), base.sorted_positions.data(),
                            base.sorted_positions.size() * sizeof(glm::vec3)), 0);
      EXPECT_EQ(wide.longest_edge, base.longest_edge);
      EXPECT_GT(base.longest_edge, 0.0f);
    }
}

}  // namespace

// The grading pass's AVX2 pair pass (where the CPU has it: two rows of 5 to 8 corners side by side
// in eight lanes) gives the baseline's bits (SSE2 lanes per row, scalar rows): weights, order, sorted
// positions and face sums, with and without the boost, on the bunny, a bumpy sphere, a CAD part
// (creases) and an open grid (boundaries), and on copies with their vertices renumbered (so that
// rows of any kind meet in a pair) and partly collapsed (degenerate edges and faces); on a CPU
// without AVX2 both runs take the baseline.
TEST(Grading, Avx2PathsGiveTheBaselineBits) {
  std::vector<Mesh> meshes = {test::makeBumpySphere(60, 80), test::makeCadPart(), test::makeGrid(30, 2.0f)};
  if (test::fileExists(test::bunnyPath())) {
    meshes.emplace_back();
    ASSERT_TRUE(readObj(test::bunnyPath(), meshes.back()).ok());
  }
  for (size_t i = 0, n = meshes.size(); i < n; ++i) {
    meshes.push_back(shuffledVertices(meshes[i], 7u + static_cast<uint32_t>(i), 0));
    meshes.push_back(shuffledVertices(meshes[i], 11u + static_cast<uint32_t>(i), 7));
  }
  for (size_t i = 0; i < meshes.size(); ++i) expectAvx2GivesTheBaselineBits(meshes[i], "mesh " + std::to_string(i));
}

// The same on triangle soups whose fans are anything but closed: each triangle joins a vertex to
// two others at most 4 (or 6) indices on (some the same one: degenerate faces), so that rows of 5 to 8
// corners hold neighbours repeated 1 to 4 times, and fans where every a matches exactly one b but
// some b none (the pair pass's closed-fan test needs both its row and its column sums). Nearly
// flat (z within 1e-3) with the triangles wound one way, so the crease term stays low and the
// boundary flag decides the boosted weights.
TEST(Grading, Avx2PathsGiveTheBaselineBitsOnNonManifoldFans) {
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::uniform_int_distribution<uint32_t> step(1, seed <= 3 ? 4 : 6);
    Mesh m;
    const uint32_t vn = 3000;
    for (uint32_t v = 0; v < vn; ++v) m.positions.push_back({unit(rng), unit(rng), 1e-3f * unit(rng)});
    for (uint32_t t = 0; t < 2 * vn; ++t) {
      const uint32_t i0 = static_cast<uint32_t>(rng() % (vn - 8));
      uint32_t i1 = i0 + step(rng), i2 = i0 + step(rng);
      const glm::vec3 d1 = m.positions[i1] - m.positions[i0], d2 = m.positions[i2] - m.positions[i0];
      if (d1.x * d2.y - d1.y * d2.x < 0.0f) std::swap(i1, i2);
      m.triangles.insert(m.triangles.end(), {i0, i1, i2});
    }
    expectAvx2GivesTheBaselineBits(m, "soup " + std::to_string(seed));
  }
  // fans made to measure, two centres side by side (vertices 18 g and 18 g + 1, so that they meet
  // in a pair; their 16 neighbours hold fewer than 5 corners each), each centre one of:
  // - a closed fan of 6;
  // - corner pairs (a, b) (u, w) (u, p) (p, q) (q, u) and a closed fan of 4: every a equals one b,
  //   but u is two a and one b, and w no a (the closed-fan test needs the column sums);
  // - (w, u) (p, u) (q, p) (u, q) and a closed fan of 4: every b equals one a, but w is no b (it
  //   needs the row sums);
  // - a closed fan of 5 with one triangle twice;
  // - the second kind with (s, t) (t, s) in place of the fan of 4, out of plane, w far out.
  // The planar ones lie in z = 0 around their centre, wound counter-clockwise (all normals +z, no
  // crease), so that the boundary flag decides their boosted weights. The triangles in random order.
  for (uint32_t seed = 1; seed <= 4; ++seed) {
    std::mt19937 rng(100 + seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    Mesh m;
    std::vector<std::array<uint32_t, 3>> tris;
    for (uint32_t g = 0; g < 400; ++g) {
      m.positions.resize(18 * g + 18);
      for (uint32_t c = 18 * g; c < 18 * g + 2; ++c) {
        const glm::vec3 centre(10.0f * unit(rng), 10.0f * unit(rng), 0.0f);
        m.positions[c] = centre;
        const uint32_t n0 = 18 * g + 2 + 8 * (c - 18 * g);
        // neighbour n0 + j at `degrees` around the centre, at a random distance in [0.5, 1.5]
        auto place = [&](uint32_t j, float degrees) {
          const float r = 1.0f + 0.5f * unit(rng), a = degrees * 3.14159265f / 180.0f;
          m.positions[n0 + j] = centre + glm::vec3(r * std::cos(a), r * std::sin(a), 0.0f);
        };
        auto pairs = [&](std::initializer_list<std::array<uint32_t, 2>> list) {
          for (const auto& ab : list) tris.push_back({c, n0 + ab[0], n0 + ab[1]});
        };
        const uint32_t kind = rng() % 5;
        if (kind == 0 || kind == 3) {
          const uint32_t n = kind == 0 ? 6 : 5;
          for (uint32_t j = 0; j < n; ++j) place(j, 360.0f * float(j) / float(n) + 10.0f * unit(rng));
          for (uint32_t j = 0; j < n; ++j) pairs({{j, (j + 1) % n}});
          if (kind == 3) tris.push_back(tris.back());
          continue;
        }
        const uint32_t u = 0, w = 1, p = 2, q = 3, s = 4, t = 5, x = 6, y = 7;
        place(u, 0.0f);
        if (kind == 1 || kind == 4) {
          place(w, 30.0f), place(p, 120.0f), place(q, 240.0f);
          pairs({{u, w}, {u, p}, {p, q}, {q, u}});
        } else {
          place(w, 330.0f), place(q, 120.0f), place(p, 240.0f);
          pairs({{w, u}, {p, u}, {q, p}, {u, q}});
        }
        if (kind == 4) {
          for (uint32_t j : {s, t}) m.positions[n0 + j] = centre + glm::vec3(unit(rng), unit(rng), unit(rng));
          m.positions[n0 + w] = centre + 3.0f * (m.positions[n0 + w] - centre);
          pairs({{s, t}, {t, s}});
        } else {
          place(s, 45.0f), place(t, 135.0f), place(x, 225.0f), place(y, 315.0f);
          pairs({{s, t}, {t, x}, {x, y}, {y, s}});
        }
      }
    }
    std::shuffle(tris.begin(), tris.end(), rng);
    for (const auto& t : tris) m.triangles.insert(m.triangles.end(), t.begin(), t.end());
    expectAvx2GivesTheBaselineBits(m, "fans " + std::to_string(seed));
  }
}

// The order is the stable sort of the referenced vertices by descending raw weight (ties by vertex
// index) and the weights are raw / longest edge, whichever way prepareMesh sorts: on the calling
// thread below 8 k referenced vertices or with one thread allowed, else two halves of the vertex
// range sorted side by side and merged. Meshes on both sides of that size, with many ties (the flat grid's interior weighs 0),
// unreferenced and point-only vertices scattered by a renumbering (so the halves hold unequal
// counts), and one with every referenced vertex in the upper half.
TEST(Grading, PreparedOrderIsTheStableSortByRawWeight) {
  std::vector<Mesh> meshes = {test::makeBumpySphere(20, 30), test::makeBumpySphere(100, 200), test::makeGrid(150, 2.0f)};
  if (test::fileExists(test::bunnyPath())) {
    meshes.emplace_back();
    ASSERT_TRUE(readObj(test::bunnyPath(), meshes.back()).ok());
  }
  {
    Mesh m = test::makeGrid(150, 2.0f);
    const size_t vn = m.vertexCount();
    for (size_t v = 0; v < 6000; ++v) m.positions.push_back({float(v % 7), 3.0f, float(v % 5)});
    for (size_t v = vn; v < m.vertexCount(); v += 3) m.points.push_back(static_cast<uint32_t>(v));
    meshes.push_back(shuffledVertices(m, 5u, 0));
    Mesh high = test::makeBumpySphere(100, 200);  // every referenced vertex above the first half
    const uint32_t shift = static_cast<uint32_t>(high.vertexCount() + 10);
    high.positions.insert(high.positions.begin(), shift, glm::vec3(0.0f));
    for (uint32_t& i : high.triangles) i += shift;
    meshes.push_back(high);
  }
  for (size_t i = 0; i < meshes.size(); ++i) {
    const Mesh& m = meshes[i];
    SCOPED_TRACE("mesh " + std::to_string(i));
    PreparedMesh p, serial;
    ASSERT_TRUE(prepareMesh(m, ClusterParams(), p).ok());
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
      ASSERT_TRUE(prepareMesh(m, ClusterParams(), serial).ok());
    }
    EXPECT_EQ(serial.order, p.order);
    ASSERT_EQ(serial.sorted_positions.size(), p.sorted_positions.size());
    EXPECT_EQ(std::memcmp(serial.sorted_positions.data(), p.sorted_positions.data(),
                          p.sorted_positions.size() * sizeof(glm::vec3)), 0);
    EXPECT_EQ(std::memcmp(serial.weights.data(), p.weights.data(), p.weights.size() * sizeof(float)), 0);
    std::vector<float> w, raw;
    float longest = 0.0f;
    gradeVertices(m, Grading::kLowTan, true, w, nullptr, &longest, &raw);
    std::vector<uint8_t> referenced(m.vertexCount(), 0);
    for (uint32_t v : m.triangles) referenced[v] = 1;
    for (uint32_t v : m.edges) referenced[v] = 1;
    for (uint32_t v : m.points) referenced[v] = 1;
    std::vector<uint32_t> expected;
    for (size_t v = 0; v < m.vertexCount(); ++v)
      if (referenced[v]) expected.push_back(static_cast<uint32_t>(v));
    auto bits = [&](uint32_t v) {
      uint32_t b;
      std::memcpy(&b, &raw[v], sizeof b);
      return b;
    };
    std::stable_sort(expected.begin(), expected.end(), [&](uint32_t a, uint32_t b) { return bits(a) > bits(b); });
    EXPECT_EQ(p.order, expected);
    ASSERT_EQ(p.sorted_positions.size(), expected.size());
    for (size_t k = 0; k < expected.size(); ++k)
      ASSERT_EQ(std::memcmp(&p.sorted_positions[k], &m.positions[expected[k]], sizeof(glm::vec3)), 0) << k;
    ASSERT_EQ(p.weights.size(), w.size());
    EXPECT_EQ(std::memcmp(p.weights.data(), w.data(), w.size() * sizeof(float)), 0);
    EXPECT_EQ(p.longest_edge, longest);
  }
}

// prepareMesh checks the coordinates and the triangle and edge indices in its own first passes:
// a bad mesh gets validateMesh's error (the same first bad element when several are bad), and the
// PreparedMesh passed in is left as it was
TEST(Grading, PrepareGivesValidateMeshsErrorAndLeavesTheOutputAlone) {
  const Mesh good = test::makeBumpySphere(12, 16);
  const size_t vn = good.vertexCount();
  const uint32_t bad_index = static_cast<uint32_t>(vn) + 3;
  std::vector<std::pair<std::string, Mesh>> cases;
  auto add = [&](const std::string& name, auto&& edit) {
    Mesh m = good;
    edit(m);
    cases.emplace_back(name, m);
  };
  add("nan vertex", [&](Mesh& m) { m.positions[7].y = std::nanf(""); });
  add("infinite vertex and a bad index", [&](Mesh& m) {
    m.positions[9].z = INFINITY;
    m.positions[4].x = -INFINITY;
    m.triangles[0] = bad_index;
  });
  add("two bad triangle indices", [&](Mesh& m) {
    m.triangles[3 * 40 + 2] = bad_index;
    m.triangles[3 * 11 + 1] = bad_index + 1;
  });
  add("the last triangle index", [&](Mesh& m) { m.triangles.back() = static_cast<uint32_t>(vn); });
  add("index 2^32 - 1", [&](Mesh& m) { m.triangles[5] = UINT32_MAX; });
  add("a bad edge index", [&](Mesh& m) { m.edges = {0, 1, 2, bad_index, bad_index, 3}; });
  add("bad edge and triangle indices", [&](Mesh& m) {
    m.edges = {0, bad_index};
    m.triangles[100] = bad_index;
  });
  add("triangle count not a multiple of 3 and a nan", [&](Mesh& m) {
    m.triangles.push_back(0);
    m.positions[3].x = std::nanf("");
  });
  add("normals count and a bad index", [&](Mesh& m) {
    m.normals.assign(vn - 1, glm::vec3(0, 0, 1));
    m.triangles[0] = bad_index;
  });
  add("a bad point index", [&](Mesh& m) { m.points = {1, bad_index}; });
  add("a bad point and a bad triangle index", [&](Mesh& m) {
    m.points = {bad_index};
    m.triangles[8] = bad_index;
  });
  add("a negative thickness", [&](Mesh& m) {
    m.edges = {0, 1, 1, 2};
    m.edge_thickness = {0.5f, -1.0f};
  });
  add("no vertices", [&](Mesh& m) { m.positions.clear(); });
  PreparedMesh kept;
  ASSERT_TRUE(prepareMesh(good, ClusterParams(), kept).ok());
  const std::vector<uint32_t> kept_order = kept.order;
  for (const auto& [name, m] : cases) {
    SCOPED_TRACE(name);
    const Error expected = validateMesh(m, "case");
    ASSERT_FALSE(expected.ok());
    PreparedMesh p = kept;
    const Error e = prepareMesh(m, ClusterParams(), p, "case");
    EXPECT_EQ(e.status, expected.status);
    EXPECT_EQ(e.message, expected.message);
    EXPECT_EQ(p.order, kept_order);
    EXPECT_EQ(p.mesh, &good);
  }
}
