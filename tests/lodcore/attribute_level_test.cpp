// Clustering levels of meshes with attributes (docs/CLUSTERING.md, "Attributes"): welding of
// non-indexed inputs, UV seams, tangent signs, triangle groups, skins, source vertices, bad input.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <tuple>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/mesh_attributes.h"

using namespace scenelod;

namespace {

constexpr LodMethod kMethods[] = {LodMethod::kUniform, LodMethod::kFloatingHeaviest, LodMethod::kFloatingNearest};

ClusterParams params(LodMethod method, float width) {
  ClusterParams p;
  p.method = method;
  p.cell_width = width;
  return p;
}

// `g` with texture coordinates (x, y), written non-indexed (three fresh vertices per triangle, as
// the glTF Fox is)
Mesh nonIndexed(const Mesh& g) {
  Mesh m;
  for (uint32_t i : g.triangles) {
    m.triangles.push_back(static_cast<uint32_t>(m.positions.size()));
    m.positions.push_back(g.positions[i]);
    m.uvs.emplace_back(g.positions[i].x, g.positions[i].y);
  }
  return m;
}

// a grid of n x n quads over [0, 1]^2 with planar texture coordinates, non-indexed
Mesh nonIndexedGrid(int n) { return nonIndexed(test::makeGrid(n, 1.0f)); }

// a box whose six faces (each its own vertices, n x n quads) lie in six squares of texture space:
// face f in [2f, 2f + 1] x [0, 1], so every box edge is a UV seam
Mesh seamedBox(int n) {
  Mesh m = test::makeBox(glm::vec3(-1.0f), glm::vec3(1.0f), n);
  const size_t per_face = size_t(n + 1) * size_t(n + 1);
  for (size_t v = 0; v < m.vertexCount(); ++v) {
    const size_t f = v / per_face, k = v % per_face;
    m.uvs.emplace_back(2.0f * float(f) + float(k % size_t(n + 1)) / float(n), float(k / size_t(n + 1)) / float(n));
  }
  return m;
}

// the face (0..5) whose texture square holds uv
int faceOfUv(const glm::vec2& uv) { return static_cast<int>(std::floor(uv.x * 0.5f)); }

// the grid of makeGrid with its left half (x < 0.5) in triangle group 0, its right half in group 1
Mesh twoMaterialGrid(int n) {
  Mesh m = test::makeGrid(n, 1.0f);
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const glm::vec3 c = (m.positions[m.triangles[3 * t]] + m.positions[m.triangles[3 * t + 1]] +
                         m.positions[m.triangles[3 * t + 2]]) / 3.0f;
    m.triangle_groups.push_back(c.x < 0.5f ? 0u : 1u);
  }
  return m;
}

std::set<std::tuple<float, float, float>> positionSet(const Mesh& m) {
  std::set<std::tuple<float, float, float>> s;
  for (const glm::vec3& p : m.positions) s.insert({p.x, p.y, p.z});
  return s;
}

}  // namespace

TEST(AttributeLevel, NonIndexedInputIsWeldedIntoFewCharts) {
  const Mesh in = nonIndexedGrid(24);
  ASSERT_EQ(in.vertexCount(), 3 * in.triangleCount());
  for (LodMethod method : kMethods) {
    Mesh out;
    ASSERT_TRUE(clusterMesh(in, params(method, 0.1f), out).ok());
    ASSERT_TRUE(validateMesh(out, "level").ok());
    ASSERT_GT(out.triangleCount(), 20u);
    ASSERT_EQ(out.uvs.size(), out.vertexCount());
    // one chart, and vertices shared by triangles (not three per triangle, as a chart per triangle gives)
    std::vector<uint32_t> chart;
    EXPECT_EQ(computeUvCharts(out, chart), 1u) << lodMethodName(method);
    EXPECT_LT(out.vertexCount(), out.triangleCount()) << lodMethodName(method);
    // planar texture coordinates stay planar: each vertex's uv is its position's, within the cell
    for (size_t v = 0; v < out.vertexCount(); ++v)
      EXPECT_LT(glm::length(out.uvs[v] - glm::vec2(out.positions[v])), 0.1f) << lodMethodName(method);
  }
}

TEST(AttributeLevel, SeamedBoxKeepsBothSidesOfEverySeam) {
  const Mesh in = seamedBox(12);
  for (LodMethod method : kMethods) {
    Mesh out;
    ASSERT_TRUE(clusterMesh(in, params(method, 0.35f), out).ok());
    ASSERT_TRUE(validateMesh(out, "level").ok());
    ASSERT_GT(out.triangleCount(), 50u);
    // each triangle's corners in one face's square, and on that face (the face's plane within a cell)
    std::map<std::tuple<float, float, float>, std::set<int>> faces_at;
    for (size_t t = 0; t < out.triangleCount(); ++t) {
      const int f = faceOfUv(out.uvs[out.triangles[3 * t]]);
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = out.triangles[3 * t + k];
        EXPECT_EQ(faceOfUv(out.uvs[v]), f) << lodMethodName(method);
        faces_at[{out.positions[v].x, out.positions[v].y, out.positions[v].z}].insert(f);
      }
    }
    // at positions on a box edge (two coordinates at +-1 within the cell), vertices of both sides
    size_t seam_positions = 0;
    for (const auto& [p, faces] : faces_at) {
      const glm::vec3 q(std::get<0>(p), std::get<1>(p), std::get<2>(p));
      int outside = 0;
      for (int a = 0; a < 3; ++a) outside += std::fabs(q[a]) > 0.9f;
      if (outside < 2) continue;
      ++seam_positions;
      EXPECT_GE(faces.size(), 2u) << lodMethodName(method) << " at " << q.x << " " << q.y << " " << q.z;
    }
    EXPECT_GT(seam_positions, 12u) << lodMethodName(method);
  }
}

TEST(AttributeLevel, TwoMaterialsStaySeparateAtEveryLevel) {
  const Mesh in = twoMaterialGrid(32);
  for (LodMethod method : kMethods) {
    for (float width : {0.05f, 0.1f, 0.2f, 0.4f}) {
      Mesh out;
      ASSERT_TRUE(clusterMesh(in, params(method, width), out).ok());
      ASSERT_TRUE(validateMesh(out, "level").ok());
      ASSERT_EQ(out.triangle_groups.size(), out.triangleCount());
      std::vector<int> group_of_vertex(out.vertexCount(), -1);
      std::set<uint32_t> groups;
      for (size_t t = 0; t < out.triangleCount(); ++t) {
        const uint32_t g = out.triangle_groups[t];
        groups.insert(g);
        for (int k = 0; k < 3; ++k) {
          int& seen = group_of_vertex[out.triangles[3 * t + k]];
          EXPECT_TRUE(seen < 0 || seen == int(g)) << "a vertex shared by both materials";
          seen = int(g);
        }
      }
      if (out.triangleCount() >= 2) { EXPECT_EQ(groups.size(), 2u) << lodMethodName(method) << " at " << width; }
    }
  }
}

TEST(AttributeLevel, StrippedMeshClustersAsThePlainPath) {
  // an indexed mesh (welding removes nothing): the same assignment, so the same representatives and
  // the same surviving cluster triangles; only the vertices split by attribute group differ
  Mesh in = test::makeSphere(glm::vec3(0.0f), 1.0f, 24, 48);
  for (const glm::vec3& p : in.positions) in.uvs.emplace_back(p.x, p.y);
  Mesh stripped = in;
  stripped.uvs.clear();
  for (LodMethod method : kMethods) {
    Mesh with, without;
    float e_with = 0.0f, e_without = 0.0f;
    ASSERT_TRUE(clusterMesh(in, params(method, 0.3f), with, &e_with).ok());
    ASSERT_TRUE(clusterMesh(stripped, params(method, 0.3f), without, &e_without).ok());
    EXPECT_EQ(with.triangleCount(), without.triangleCount()) << lodMethodName(method);
    EXPECT_EQ(positionSet(with), positionSet(without)) << lodMethodName(method);
    EXPECT_EQ(e_with, e_without) << lodMethodName(method);
    EXPECT_FALSE(with.uvs.empty());
  }
}

TEST(AttributeLevel, MirroredTangentFramesKeepBothSigns) {
  // a grid whose left half's texture is mirrored (u = -x): tangent -x with sign -1 there, +x with
  // sign +1 on the right; the vertices on the mirror line are split by sign
  Mesh in = test::makeGrid(32, 1.0f);
  Mesh split;
  for (size_t t = 0; t < in.triangleCount(); ++t) {
    const glm::vec3 c = (in.positions[in.triangles[3 * t]] + in.positions[in.triangles[3 * t + 1]] +
                         in.positions[in.triangles[3 * t + 2]]) / 3.0f;
    const bool mirrored = c.x < 0.5f;
    for (int k = 0; k < 3; ++k) {
      const glm::vec3& p = in.positions[in.triangles[3 * t + k]];
      split.triangles.push_back(static_cast<uint32_t>(split.positions.size()));
      split.positions.push_back(p);
      split.uvs.emplace_back(mirrored ? -p.x : p.x, p.y);
      split.tangents.push_back(mirrored ? glm::vec4(-1, 0, 0, -1) : glm::vec4(1, 0, 0, 1));
    }
  }
  for (LodMethod method : kMethods) {
    Mesh out;
    ASSERT_TRUE(clusterMesh(split, params(method, 0.12f), out).ok());
    ASSERT_TRUE(validateMesh(out, "level").ok());
    ASSERT_EQ(out.tangents.size(), out.vertexCount());
    size_t negative = 0, positive = 0;
    for (size_t v = 0; v < out.vertexCount(); ++v) {
      const glm::vec4& t = out.tangents[v];
      EXPECT_NEAR(glm::length(glm::vec3(t)), 1.0f, 1e-5f);
      EXPECT_NEAR(glm::dot(glm::vec3(t), out.normals[v]), 0.0f, 1e-5f);
      // a vertex mixing both sides would average -x and +x to nothing
      EXPECT_GT(t.x * t.w, 0.99f) << lodMethodName(method) << " vertex " << v;
      (t.w < 0.0f ? negative : positive)++;
    }
    EXPECT_GT(negative, 10u) << lodMethodName(method);
    EXPECT_GT(positive, 10u) << lodMethodName(method);
    // no triangle mixes the signs
    for (size_t t = 0; t < out.triangleCount(); ++t) {
      EXPECT_EQ(out.tangents[out.triangles[3 * t]].w, out.tangents[out.triangles[3 * t + 1]].w);
      EXPECT_EQ(out.tangents[out.triangles[3 * t]].w, out.tangents[out.triangles[3 * t + 2]].w);
    }
  }
  // no tangents in, none out
  Mesh plain_uvs = split;
  plain_uvs.tangents.clear();
  Mesh out;
  ASSERT_TRUE(clusterMesh(plain_uvs, params(LodMethod::kFloatingNearest, 0.12f), out).ok());
  EXPECT_TRUE(out.tangents.empty());
}

TEST(AttributeLevel, BadAttributesGiveErrorsNamingTheAttribute) {
  const Mesh good = seamedBox(2);
  auto expectError = [&](Mesh m, const char* attribute) {
    Mesh out;
    const Error e = clusterMesh(m, params(LodMethod::kFloatingNearest, 0.5f), out);
    EXPECT_FALSE(e.ok()) << attribute;
    EXPECT_NE(e.message.find(attribute), std::string::npos) << e.message;
    EXPECT_NE(e.message.find("mesh"), std::string::npos) << e.message;
  };
  Mesh m = good;
  m.uvs.pop_back();
  expectError(m, "texture coordinates");
  m = good;
  m.uvs[3].y = std::numeric_limits<float>::quiet_NaN();
  expectError(m, "texture coordinates");
  m = good;
  m.extra_uvs.push_back(std::vector<glm::vec2>(m.vertexCount() - 1));
  expectError(m, "texture coordinates (set 1)");
  m = good;
  m.tangents.assign(m.vertexCount() - 1, glm::vec4(1, 0, 0, 1));
  expectError(m, "tangents");
  m = good;
  m.joints.assign(m.vertexCount(), glm::u16vec4(0, 1, 0, 0));
  m.weights.assign(m.vertexCount(), glm::vec4(0.5f, 0.5f, 0, 0));
  m.joint_parents = {-1, 0};
  Mesh skinned = m;
  m.weights[5].x = std::numeric_limits<float>::quiet_NaN();
  expectError(m, "skin weights");
  m = skinned;
  m.weights[5] = glm::vec4(0.0f);
  expectError(m, "skin weight");
  m = skinned;
  m.joints[7].z = 2;
  expectError(m, "joint 2");
  m = skinned;
  m.weights.pop_back();
  expectError(m, "skin");
  m = good;
  m.triangle_groups.assign(m.triangleCount() - 1, 0);
  expectError(m, "triangle groups");
}

namespace {

// weights sum to 1, are non-negative, and unused slots are joint 0 with weight 0
void expectNormalisedSkin(const Mesh& out) {
  ASSERT_EQ(out.joints.size(), out.vertexCount());
  ASSERT_EQ(out.weights.size(), out.vertexCount());
  for (size_t v = 0; v < out.vertexCount(); ++v) {
    const glm::vec4& w = out.weights[v];
    EXPECT_NEAR(w.x + w.y + w.z + w.w, 1.0f, 1e-5f);
    for (int k = 0; k < 4; ++k) {
      EXPECT_GE(w[k], 0.0f);
      if (w[k] == 0.0f) { EXPECT_EQ(out.joints[v][k], 0u); }
    }
  }
}

// two limbs (cylinders along x) touching along y = 0, bound to two unrelated bone chains:
// 1 -> 2 for the upper limb, 3 -> 4 for the lower, all children of the root 0; each vertex also
// gives a little weight to the root and to one of three leaf joints 5, 6, 7
Mesh touchingLimbs() {
  const float r = 0.25f;
  Mesh m = test::makeCylinder(0.0f, 2.0f, r, 16, 16, glm::vec3(0, r, 0));
  const size_t upper = m.vertexCount();
  test::appendMesh(m, test::makeCylinder(0.0f, 2.0f, r, 16, 16, glm::vec3(0, -r, 0)));
  for (size_t v = 0; v < m.vertexCount(); ++v) {
    const float t = std::clamp(m.positions[v].x * 0.5f, 0.0f, 1.0f);
    const uint16_t root = v < upper ? 1 : 3;
    m.joints.push_back(glm::u16vec4(root, root + 1, 0, 5 + v % 3));
    m.weights.push_back(glm::vec4(0.85f * (1.0f - t), 0.85f * t, 0.1f, 0.05f));
  }
  m.joint_parents = {-1, 0, 1, 0, 3, 0, 0, 0};
  return m;
}

}  // namespace

TEST(AttributeLevel, SkinWeightsAreTheClustersTopFour) {
  // one cluster (a quad far smaller than the cell) collapsing to a point
  Mesh m;
  m.positions = {{0, 0, 0}, {0.01f, 0, 0}, {0.01f, 0.01f, 0}, {0, 0.01f, 0}};
  m.triangles = {0, 1, 2, 0, 2, 3};
  m.joints = {{1, 2, 3, 4}, {1, 5, 0, 0}, {1, 0, 0, 0}, {1, 2, 6, 0}};
  m.weights = {{0.4f, 0.3f, 0.2f, 0.1f}, {0.5f, 0.5f, 0, 0}, {1, 0, 0, 0}, {0.4f, 0.3f, 0.3f, 0}};
  Mesh out;
  ASSERT_TRUE(clusterMesh(m, params(LodMethod::kUniform, 1.0f), out).ok());
  ASSERT_EQ(out.vertexCount(), 1u);
  ASSERT_EQ(out.pointCount(), 1u);
  // sums: joint 1 2.3, 2 0.6, 5 0.5, 6 0.3, 3 0.2, 4 0.1: the first four, over 3.7
  EXPECT_EQ(out.joints[0], glm::u16vec4(1, 2, 5, 6));
  EXPECT_NEAR(out.weights[0].x, 2.3f / 3.7f, 1e-6f);
  EXPECT_NEAR(out.weights[0].y, 0.6f / 3.7f, 1e-6f);
  EXPECT_NEAR(out.weights[0].z, 0.5f / 3.7f, 1e-6f);
  EXPECT_NEAR(out.weights[0].w, 0.3f / 3.7f, 1e-6f);
}

TEST(AttributeLevel, UnrelatedLimbsNeverShareACluster) {
  Mesh in = touchingLimbs();
  for (bool skeleton : {true, false}) {
    if (!skeleton) in.joint_parents.clear();
    for (LodMethod method : kMethods) {
      for (float width : {0.2f, 0.4f, 0.8f}) {
        Mesh out;
        ASSERT_TRUE(clusterMesh(in, params(method, width), out).ok());
        ASSERT_TRUE(validateMesh(out, "level").ok()) << validateMesh(out, "level").message;
        expectNormalisedSkin(out);
        size_t mixed = 0;
        for (size_t v = 0; v < out.vertexCount(); ++v) {
          bool upper = false, lower = false;
          for (int k = 0; k < 4; ++k) {
            if (out.weights[v][k] == 0.0f) continue;
            upper |= out.joints[v][k] == 1 || out.joints[v][k] == 2;
            lower |= out.joints[v][k] == 3 || out.joints[v][k] == 4;
          }
          mixed += upper && lower;
        }
        EXPECT_EQ(mixed, 0u) << lodMethodName(method) << " at " << width << (skeleton ? "" : " without skeleton");
      }
    }
  }
}

TEST(AttributeLevel, AllGroupsOfAClusterShareItsSkinWeights) {
  Mesh in = seamedBox(8);
  for (const glm::vec3& p : in.positions) {
    in.joints.push_back(glm::u16vec4(1, 2, 0, 0));
    in.weights.push_back(glm::vec4(0.5f * (p.x + 1.0f) + 0.01f, 0.5f * (1.0f - p.x) + 0.01f, 0, 0));
  }
  in.joint_parents = {-1, 0, 1};
  for (LodMethod method : kMethods) {
    Mesh out;
    ASSERT_TRUE(clusterMesh(in, params(method, 0.5f), out).ok());
    expectNormalisedSkin(out);
    std::map<std::tuple<float, float, float>, size_t> first_at;
    size_t shared = 0;
    for (size_t v = 0; v < out.vertexCount(); ++v) {
      const auto [it, fresh] = first_at.insert({{out.positions[v].x, out.positions[v].y, out.positions[v].z}, v});
      if (fresh) continue;
      ++shared;
      EXPECT_EQ(out.joints[v], out.joints[it->second]);
      EXPECT_EQ(out.weights[v], out.weights[it->second]);
    }
    EXPECT_GT(shared, 8u) << lodMethodName(method);  // the seams' clusters have several groups
  }
}

namespace {

// every level vertex's source is an input vertex within the level's max_error of it
void expectSourcesWithinError(const Mesh& in, const Mesh& level, const std::vector<uint32_t>& source,
                              float max_error, const char* what) {
  ASSERT_EQ(source.size(), level.vertexCount()) << what;
  for (size_t v = 0; v < source.size(); ++v) {
    ASSERT_LT(source[v], in.vertexCount()) << what;
    EXPECT_LE(glm::length(in.positions[source[v]] - level.positions[v]), max_error * 1.0001f + 1e-7f) << what;
  }
}

}  // namespace

TEST(AttributeLevel, ChainLevelsKeepAttributesAndRecordSourceVertices) {
  Mesh in = nonIndexed(test::makeSphere(glm::vec3(0.0f), 1.0f, 24, 48));
  in.triangle_groups.resize(in.triangleCount());
  for (size_t t = 0; t < in.triangleCount(); ++t) in.triangle_groups[t] = t % 7 < 3 ? 0u : 1u;
  for (LodMethod method : kMethods) {
    ChainParams cp;
    cp.cluster.method = method;
    cp.level_count = 4;
    LodChain chain;
    ASSERT_TRUE(buildChain(in, cp, chain).ok());
    ASSERT_EQ(chain.levelCount(), 5u);
    EXPECT_EQ(chain.levels[0].mesh.vertexCount(), in.vertexCount());  // level 0 is the input, unwelded
    EXPECT_TRUE(chain.levels[0].source_vertex.empty());
    for (size_t k = 1; k < chain.levelCount(); ++k) {
      const LodLevel& level = chain.levels[k];
      ASSERT_TRUE(validateMesh(level.mesh, "level").ok()) << validateMesh(level.mesh, "level").message;
      EXPECT_EQ(level.mesh.uvs.size(), level.mesh.vertexCount());
      EXPECT_EQ(level.mesh.triangle_groups.size(), level.mesh.triangleCount());
      EXPECT_GT(level.max_error, 0.0f);
      EXPECT_GT(level.cell_width, chain.levels[k - 1].cell_width);
      expectSourcesWithinError(in, level.mesh, level.source_vertex, level.max_error, lodMethodName(method));
    }
    // the first level has about half the input's triangles (the w_1 search ran on the welded mesh)
    EXPECT_NEAR(double(chain.levels[1].mesh.triangleCount()) / double(in.triangleCount()), 0.5, 0.1);
    // the same chain on any number of threads, and from a handed-over mesh
    LodChain again;
    Mesh copy = in;
    ASSERT_TRUE(buildChain(std::move(copy), cp, again).ok());
    EXPECT_TRUE(copy.positions.empty());
    for (size_t k = 1; k < chain.levelCount(); ++k) {
      EXPECT_EQ(again.levels[k].mesh.positions, chain.levels[k].mesh.positions);
      EXPECT_EQ(again.levels[k].source_vertex, chain.levels[k].source_vertex);
    }
    EXPECT_EQ(again.levels[0].mesh.positions, in.positions);
  }
}

TEST(AttributeLevel, SourceVerticesOfSingleLevels) {
  const Mesh with = nonIndexedGrid(16);
  const Mesh without = test::makeSphere(glm::vec3(0.0f), 1.0f, 16, 32);
  for (LodMethod method : kMethods) {
    for (const Mesh* in : {&with, &without}) {
      Mesh out;
      ClusterOutputs outputs;
      ASSERT_TRUE(clusterMesh(*in, params(method, in == &with ? 0.15f : 0.3f), out, outputs).ok());
      ASSERT_GT(out.vertexCount(), 0u);
      EXPECT_EQ(outputs.stats.cluster_count > 0, true);
      expectSourcesWithinError(*in, out, outputs.source_vertex, outputs.stats.max_error, lodMethodName(method));
      // the plain overload gives the same level
      Mesh plain;
      float max_error = -1.0f;
      ASSERT_TRUE(clusterMesh(*in, params(method, in == &with ? 0.15f : 0.3f), plain, &max_error).ok());
      EXPECT_EQ(plain.positions, out.positions);
      EXPECT_EQ(plain.triangles, out.triangles);
      EXPECT_EQ(max_error, outputs.stats.max_error);
    }
  }
}

TEST(AttributeLevel, OneGroupOtherThanZeroIsKeptByThePlainPath) {
  Mesh in = test::makeSphere(glm::vec3(0.0f), 1.0f, 16, 32);
  in.triangle_groups.assign(in.triangleCount(), 5u);
  Mesh out;
  ASSERT_TRUE(clusterMesh(in, params(LodMethod::kFloatingNearest, 0.3f), out).ok());
  ASSERT_GT(out.triangleCount(), 0u);
  EXPECT_EQ(out.triangle_groups, std::vector<uint32_t>(out.triangleCount(), 5u));
  EXPECT_TRUE(out.uvs.empty());
  ChainParams cp;
  cp.level_count = 3;
  LodChain chain;
  ASSERT_TRUE(buildChain(in, cp, chain).ok());
  for (size_t k = 1; k < chain.levelCount(); ++k)
    EXPECT_EQ(chain.levels[k].mesh.triangle_groups, std::vector<uint32_t>(chain.levels[k].mesh.triangleCount(), 5u));
}

TEST(AttributeLevel, SkinWithoutTextureSplitsNoClusterByPiece) {
  // a part of several disconnected pieces, all bound to one joint: no UV seam, no bone to tell
  // apart, so the level's vertices are the plain path's (pieces sharing a cluster share its vertex)
  Mesh plain = test::makeCadPart();
  computeVertexNormals(plain);  // (the box's faces' own normals: nothing to weld, as in the plain path)
  Mesh skinned = plain;
  skinned.joints.assign(skinned.vertexCount(), glm::u16vec4(0));
  skinned.weights.assign(skinned.vertexCount(), glm::vec4(1, 0, 0, 0));
  Mesh welded = skinned;
  ASSERT_EQ(weldVertices(welded), 0u);
  for (LodMethod method : kMethods) {
    Mesh a, b;
    ASSERT_TRUE(clusterMesh(plain, params(method, 0.25f), a).ok());
    ASSERT_TRUE(clusterMesh(skinned, params(method, 0.25f), b).ok());
    EXPECT_EQ(a.vertexCount(), b.vertexCount()) << lodMethodName(method);
    EXPECT_EQ(a.triangleCount(), b.triangleCount()) << lodMethodName(method);
    EXPECT_EQ(positionSet(a), positionSet(b)) << lodMethodName(method);
  }
}
