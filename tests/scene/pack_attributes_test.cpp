// The level attributes section of LOD packs: texture coordinate sets, tangents, skins, triangle
// groups and source vertices survive a round trip (reordered or not), and hand-edited attribute
// arrays are refused. (Packs written before the section: pack_test.cpp.)
#include <algorithm>
#include <cstring>
#include <set>
#include <tuple>

#include <gtest/gtest.h>

#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/pack.h"
#include "pack_bytes.h"

using namespace scenelod;
using namespace scenelod::scene;
using scenelod::test::resign;

namespace {

// an n x n grid of quads in two triangle groups (left and right half), with every attribute
Mesh texturedSkinnedGrid(uint32_t n) {
  Mesh m;
  for (uint32_t y = 0; y <= n; ++y)
    for (uint32_t x = 0; x <= n; ++x) {
      const float u = float(x) / float(n), v = float(y) / float(n);
      m.positions.push_back({u, v, 0.1f * float((x * 7 + y * 3) % 5)});
      m.normals.push_back({0, 0, 1});
      m.colors.push_back({u, v, 0.5f});
      m.uvs.push_back({u, 1.0f - v});
      m.tangents.push_back({1, 0, 0, (x + y) % 2 ? 1.0f : -1.0f});
      m.joints.push_back({uint16_t(x % 3), uint16_t(y % 3), 0, 0});
      m.weights.push_back({0.75f, 0.25f, 0, 0});
    }
  m.extra_uvs.assign(2, {});
  for (const glm::vec2& uv : m.uvs) {
    m.extra_uvs[0].push_back(uv * 2.0f);
    m.extra_uvs[1].push_back(uv + 0.5f);
  }
  m.joint_parents = {-1, 0, 1};
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      const uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      m.triangles.insert(m.triangles.end(), {a, b, d, a, d, c});
      const uint32_t group = x < n / 2 ? 1u : 0u;  // group 1 first in the input: reordering sorts groups
      m.triangle_groups.insert(m.triangle_groups.end(), {group, group});
    }
  return m;
}

// a chain whose levels carry every attribute: level 0 the grid, level 1 a coarser grid whose vertices
// stand for grid vertices (its source_vertex), level 2 an edge and a point
void makeAttributeInput(SceneData& s, std::vector<LodChain>& chains, std::vector<Sphere>& spheres) {
  s = SceneData{};
  s.meshes.resize(1);
  s.meshes[0].name = "skinned textured plate";
  s.meshes[0].mesh = texturedSkinnedGrid(8);
  s.nodes.resize(1);
  s.nodes[0].mesh = 0;
  s.roots = {0};
  chains.assign(1, LodChain{});
  LodLevel l0;
  l0.mesh = s.meshes[0].mesh;
  chains[0].levels.push_back(l0);
  LodLevel l1;
  l1.mesh = texturedSkinnedGrid(4);
  for (uint32_t y = 0; y <= 4; ++y)
    for (uint32_t x = 0; x <= 4; ++x) l1.source_vertex.push_back(2 * y * 9 + 2 * x);
  l1.cell_width = 0.25f;
  l1.method = LodMethod::kFloatingHeaviest;
  chains[0].levels.push_back(l1);
  LodLevel l2;
  l2.mesh.positions = {{0, 0, 0}, {1, 1, 0}, {0.5f, 0.5f, 0.1f}};
  l2.mesh.uvs = {{0, 1}, {1, 0}, {0.5f, 0.5f}};
  l2.mesh.joints.assign(3, glm::u16vec4(2, 0, 0, 0));
  l2.mesh.weights.assign(3, glm::vec4(1, 0, 0, 0));
  l2.mesh.joint_parents = {-1, 0, 1};
  l2.mesh.edges = {0, 1};
  l2.mesh.points = {2};
  l2.source_vertex = {0, 80, 40};
  l2.cell_width = 0.9f;
  l2.method = LodMethod::kFloatingHeaviest;
  chains[0].levels.push_back(l2);
  spheres = {computeChainBounds(chains[0])};
}

std::vector<uint8_t> attributePack(bool optimize) {
  SceneData s;
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  makeAttributeInput(s, chains, spheres);
  PackWriteOptions o;
  o.optimize_order = optimize;
  std::vector<uint8_t> bytes;
  const Error e = writePackBytes(bytes, s, chains, spheres, o);
  EXPECT_TRUE(e.ok()) << e.message;
  return bytes;
}

// everything a triangle corner carries, to compare meshes whose vertices and triangles were reordered
using Corner = std::tuple<float, float, float, float, float, float, float, float, float, int, int, float, float>;
Corner corner(const Mesh& m, uint32_t v) {
  return Corner(m.positions[v].x, m.positions[v].y, m.positions[v].z, m.uvs[v].x, m.uvs[v].y, m.extra_uvs[1][v].x,
                m.tangents[v].w, m.colors[v].x, m.normals[v].z, m.joints[v][0], m.joints[v][1], m.weights[v][0],
                m.extra_uvs[0][v].y);
}
std::multiset<std::tuple<uint32_t, Corner, Corner, Corner>> triangleSet(const Mesh& m) {
  std::multiset<std::tuple<uint32_t, Corner, Corner, Corner>> set;
  for (size_t t = 0; t < m.triangleCount(); ++t)
    set.insert({m.triangleGroup(t), corner(m, m.triangles[3 * t]), corner(m, m.triangles[3 * t + 1]),
                corner(m, m.triangles[3 * t + 2])});
  return set;
}

// writes `value` over the first element of a view into `bytes` (a loaded copy of the same bytes), re-signed
template <class T, class V>
std::vector<uint8_t> edited(std::vector<uint8_t> bytes, const Pack& loaded, Span<const V> view, const T& value) {
  const size_t at = size_t(reinterpret_cast<const uint8_t*>(view.data) - loaded.bytes());
  std::memcpy(bytes.data() + at, &value, sizeof value);
  resign(bytes);
  return bytes;
}

// the attribute chain written (reordered or not) and loaded back
struct RoundTrip {
  SceneData scene;
  std::vector<LodChain> chains, back;
  std::vector<Sphere> spheres, back_spheres;
  std::vector<uint8_t> bytes;
  Pack pack;

  explicit RoundTrip(bool optimize) {
    makeAttributeInput(scene, chains, spheres);
    bytes = attributePack(optimize);
    const Error e = Pack::fromBytes(bytes.data(), bytes.size(), pack, "mem");
    EXPECT_TRUE(e.ok()) << e.message;
    pack.toChains(back, back_spheres);
  }
};

Error parse(const std::vector<uint8_t>& bytes) {
  Pack p;
  return Pack::fromBytes(bytes.data(), bytes.size(), p, "attributes.slodpack");
}

}  // namespace

TEST(PackAttributes, UnoptimisedRoundTripKeepsEveryAttribute) {
  const RoundTrip t(false);
  const std::vector<LodChain>&chains = t.chains, &back = t.back;
  ASSERT_EQ(back.size(), 1u);
  ASSERT_EQ(back[0].levels.size(), 3u);
  for (size_t l = 0; l < 3; ++l) {
    const LodLevel &a = chains[0].levels[l], &b = back[0].levels[l];
    SCOPED_TRACE("level " + std::to_string(l));
    auto vertices = [](const LodLevel& x) {
      return std::tie(x.mesh.positions, x.mesh.colors, x.mesh.uvs, x.mesh.extra_uvs, x.mesh.tangents, x.source_vertex);
    };
    auto skinAndGroups = [](const LodLevel& x) {
      return std::tie(x.mesh.joints, x.mesh.weights, x.mesh.joint_parents, x.mesh.triangles, x.mesh.triangle_groups);
    };
    EXPECT_TRUE(vertices(a) == vertices(b));
    EXPECT_TRUE(skinAndGroups(a) == skinAndGroups(b));
    EXPECT_TRUE(validateMesh(b.mesh, "back").ok());
  }
  const PackLevelView v = t.pack.level(0, 0);
  EXPECT_EQ(v.extra_uv_set_count, 2u);
  EXPECT_EQ(v.extra_uvs.size(), 2 * v.positions.size());
  EXPECT_EQ(v.extra_uvs[v.positions.size()], chains[0].levels[0].mesh.extra_uvs[1][0]);
  SceneData back_scene;
  t.pack.toSceneData(back_scene);
  EXPECT_EQ(back_scene.meshes[0].mesh.tangents, t.scene.meshes[0].mesh.tangents);
}

TEST(PackAttributes, ReorderedLevelsKeepTrianglesCornersGroupsAndSources) {
  const RoundTrip t(true);
  const std::vector<LodChain>&chains = t.chains, &back = t.back;
  EXPECT_NE(t.bytes, attributePack(false));  // the order did change
  ASSERT_EQ(back.size(), 1u);
  const Mesh& original = chains[0].levels[0].mesh;
  const Mesh& original_back = back[0].levels[0].mesh;
  for (size_t l = 0; l < 2; ++l) {
    const LodLevel &a = chains[0].levels[l], &b = back[0].levels[l];
    SCOPED_TRACE("level " + std::to_string(l));
    EXPECT_EQ(triangleSet(a.mesh), triangleSet(b.mesh));
    // groups are contiguous and ascending: one index range per material
    EXPECT_TRUE(std::is_sorted(b.mesh.triangle_groups.begin(), b.mesh.triangle_groups.end()));
    EXPECT_EQ(b.mesh.joint_parents, a.mesh.joint_parents);
  }
  // a reordered level's source vertex is the reordered level 0's vertex with the same attributes
  const LodLevel &a1 = chains[0].levels[1], &b1 = back[0].levels[1];
  ASSERT_EQ(b1.source_vertex.size(), b1.mesh.vertexCount());
  for (size_t v = 0; v < b1.mesh.vertexCount(); ++v) {
    const auto it = std::find(a1.mesh.positions.begin(), a1.mesh.positions.end(), b1.mesh.positions[v]);
    ASSERT_NE(it, a1.mesh.positions.end());
    const uint32_t before = a1.source_vertex[size_t(it - a1.mesh.positions.begin())];
    EXPECT_EQ(corner(original_back, b1.source_vertex[v]), corner(original, before)) << "vertex " << v;
  }
  EXPECT_TRUE(back[0].levels[0].source_vertex.empty());  // level 0: the identity
}

TEST(PackAttributes, WriterRefusesSourceVerticesOutsideLevelZeroAndEmptySets) {
  SceneData s;
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  makeAttributeInput(s, chains, spheres);
  chains[0].levels[2].source_vertex[1] = 81;  // level 0 has 81 vertices
  std::vector<uint8_t> bytes;
  Error e = writePackBytes(bytes, s, chains, spheres);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("level 2: vertex 1 has source vertex 81 but level 0 has 81 vertices"), std::string::npos) << e.message;
  chains[0].levels[2].source_vertex.pop_back();
  e = writePackBytes(bytes, s, chains, spheres);
  EXPECT_NE(e.message.find("2 source vertices for 3 vertices"), std::string::npos) << e.message;
  // an empty extra texture set, which validateMesh lets pass, has no place in the pack's layout
  chains[0].levels[2].source_vertex.push_back(40);
  chains[0].levels[2].mesh.extra_uvs.assign(2, {});
  chains[0].levels[2].mesh.extra_uvs[1].assign(3, glm::vec2(0.5f));
  e = writePackBytes(bytes, s, chains, spheres);
  EXPECT_NE(e.message.find("level 2: texture coordinate set 1 has 0 values for 3 vertices"), std::string::npos) << e.message;
}

TEST(PackAttributes, HandEditedAttributesAreRefusedEvenWithAValidChecksum) {
  const std::vector<uint8_t> bytes = attributePack(false);
  Pack good;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), good, "mem").ok());
  const PackLevelView v1 = good.level(0, 1);

  Error e = parse(edited(bytes, good, v1.joints, glm::u16vec4(0, 3, 0, 0)));  // the skeleton has 3 joints
  EXPECT_EQ(e.status, Status::kCorrupt);
  EXPECT_NE(e.message.find("attributes.slodpack: level record 1 has a skin joint out of range"), std::string::npos) << e.message;

  e = parse(edited(bytes, good, v1.source_vertex, uint32_t{81}));
  EXPECT_NE(e.message.find("level record 1 has a source vertex out of range"), std::string::npos) << e.message;
  Pack unchecked;
  const std::vector<uint8_t> bad_source = edited(bytes, good, v1.source_vertex, uint32_t{81});
  EXPECT_TRUE(Pack::fromBytes(bad_source.data(), bad_source.size(), unchecked, "mem", false).ok());

  e = parse(edited(bytes, good, v1.joint_parents, int32_t{2}));  // joint 0 its own grandchild
  EXPECT_NE(e.message.find("level record 1 has joint parents that form a cycle"), std::string::npos) << e.message;
  e = parse(edited(bytes, good, v1.joint_parents, int32_t{3}));
  EXPECT_NE(e.message.find("level record 1 has a joint parent out of range"), std::string::npos) << e.message;
}

TEST(PackAttributes, HostileAttributeRecordsAreRefused) {
  const std::vector<uint8_t> bytes = attributePack(false);
  Pack good;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), good, "mem").ok());
  // the attribute records: section 9 from the table
  uint32_t count;
  uint64_t table, records = 0, record_count = 0;
  std::memcpy(&count, bytes.data() + 28, 4);
  std::memcpy(&table, bytes.data() + 32, 8);
  size_t entry = 0;
  for (uint32_t i = 0; i < count; ++i) {
    uint32_t kind;
    std::memcpy(&kind, bytes.data() + table + 32 * i, 4);
    if (kind != 9) continue;
    entry = size_t(table + 32 * i);
    std::memcpy(&records, bytes.data() + entry + 8, 8);
    std::memcpy(&record_count, bytes.data() + entry + 16, 8);
  }
  ASSERT_NE(records, 0u);
  ASSERT_EQ(record_count, 3u);
  auto with = [&](size_t at, const auto& value) {
    std::vector<uint8_t> b = bytes;
    std::memcpy(b.data() + at, &value, sizeof value);
    resign(b);
    return parse(b);
  };
  // a texture set count whose arrays would wrap around 2^64 bytes
  Error e = with(size_t(records), uint32_t{0xffffffffu});
  EXPECT_EQ(e.status, Status::kCorrupt);
  EXPECT_NE(e.message.find("level record 0 has an attribute array outside the data section"), std::string::npos) << e.message;
  // a set count without its array, an array offset near 2^64
  e = with(size_t(records + 80 + 16), uint64_t{0});  // level 1's extra_uvs offset
  EXPECT_NE(e.message.find("level record 1 has texture coordinate sets"), std::string::npos) << e.message;
  e = with(size_t(records + 80 + 24), ~uint64_t{15});  // level 1's tangents
  EXPECT_NE(e.message.find("level record 1 has an attribute array outside the data section"), std::string::npos) << e.message;
  // fewer records than levels
  e = with(entry + 16, uint64_t{2});
  EXPECT_NE(e.message.find("section 9 has 2 level attribute records for 3 level records"), std::string::npos) << e.message;
  // a pack without the section's optional arrays (set count 0, no offsets) still loads
  std::vector<uint8_t> b = bytes;
  std::memset(b.data() + records + 2 * 80, 0, 80);
  resign(b);
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(b.data(), b.size(), p, "mem").ok());
  EXPECT_TRUE(p.level(0, 2).joints.empty() && p.level(0, 2).source_vertex.empty());
}
