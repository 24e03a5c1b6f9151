#include "scenelod/scene/pack.h"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/scene.h"
#include "pack_bytes.h"
#include "test_support.h"

using namespace scenelod;
using namespace scenelod::scene;
using scenelod::test::resign;
using scenelod::test::sectionOffset;

namespace {

Mesh grid(uint32_t n, float z) {
  Mesh m;
  for (uint32_t y = 0; y <= n; ++y)
    for (uint32_t x = 0; x <= n; ++x) {
      m.positions.push_back({float(x) / n, float(y) / n, z * float((x * 7 + y * 3) % 5)});
      m.normals.push_back({0, 0, 1});
    }
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      const uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      m.triangles.insert(m.triangles.end(), {a, b, d, a, d, c});
    }
  return m;
}

// two meshes, three objects (two instances of mesh 0), hand-made chains with an edge-and-point level
void makeInput(SceneData& s, std::vector<LodChain>& chains, std::vector<Sphere>& spheres) {
  s = SceneData{};
  s.meshes.resize(2);
  s.meshes[0].name = "plate";
  s.meshes[0].mesh = grid(12, 0.01f);
  s.meshes[1].name = "bump";
  s.meshes[1].mesh = grid(5, 0.2f);
  s.meshes[1].mesh.colors.assign(s.meshes[1].mesh.vertexCount(), glm::vec3(0.25f, 0.5f, 1.0f));
  s.nodes.resize(4);
  s.nodes[0].name = "root";
  s.nodes[0].children = {1, 2, 3};
  for (int i = 1; i < 4; ++i) {
    s.nodes[i].parent = 0;
    s.nodes[i].mesh = i == 3 ? 1 : 0;
    s.nodes[i].name = "part" + std::to_string(i);
    s.nodes[i].local = glm::translate(glm::mat4(1.0f), glm::vec3(float(i), 0.5f, -1.0f));
  }
  s.roots = {0};
  chains.assign(2, LodChain{});
  spheres.resize(2);
  for (size_t c = 0; c < 2; ++c) {
    LodLevel l0;
    l0.mesh = s.meshes[c].mesh;
    chains[c].levels.push_back(l0);
    LodLevel l1;
    l1.mesh = grid(3, 0.05f);
    l1.cell_width = 0.3f;
    l1.max_error = 0.1f;
    l1.method = LodMethod::kFloatingNearest;
    chains[c].levels.push_back(l1);
    LodLevel l2;
    l2.mesh.positions = {{0, 0, 0}, {1, 1, 0}, {0.5f, 0.5f, 0.1f}};
    l2.mesh.edges = {0, 1};
    l2.mesh.edge_thickness = {0.2f};
    l2.mesh.points = {2};
    l2.cell_width = 0.9f;
    l2.max_error = 0.6f;
    l2.method = LodMethod::kFloatingNearest;
    chains[c].levels.push_back(l2);
    spheres[c] = computeChainBounds(chains[c]);
  }
}

std::vector<uint8_t> makePack(bool optimize = true) {
  SceneData s;
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  makeInput(s, chains, spheres);
  PackWriteOptions o;
  o.optimize_order = optimize;
  o.importance = {1.0f, 0.5f, 2.0f};
  o.must_draw = {0, 1, 0};
  o.user_data = {11, 22, 33};
  std::vector<uint8_t> bytes;
  EXPECT_TRUE(writePackBytes(bytes, s, chains, spheres, o).ok());
  return bytes;
}

std::vector<glm::vec3> sorted(std::vector<glm::vec3> v) {
  std::sort(v.begin(), v.end(), [](const glm::vec3& a, const glm::vec3& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });
  return v;
}

}  // namespace

TEST(Pack, Crc32OfTheStandardCheckString) {
  EXPECT_EQ(crc32("123456789", 9), 0xCBF43926u);
  // incremental equals one-shot
  const char text[] = "The quick brown fox jumps over the lazy dog";
  EXPECT_EQ(crc32(text + 10, sizeof text - 11, crc32(text, 10)), crc32(text, sizeof text - 1));
  EXPECT_EQ(crc32(text, sizeof text - 1), 0x414FA339u);
}

TEST(Pack, UnoptimisedRoundTripGivesTheSameChainsAndScene) {
  SceneData s;
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  makeInput(s, chains, spheres);
  const std::vector<uint8_t> bytes = makePack(false);
  Pack p;
  const Error e = Pack::fromBytes(bytes.data(), bytes.size(), p, "mem");
  ASSERT_TRUE(e.ok()) << e.message;
  std::vector<LodChain> back;
  std::vector<Sphere> back_spheres;
  p.toChains(back, back_spheres);
  ASSERT_EQ(back.size(), chains.size());
  for (size_t c = 0; c < chains.size(); ++c) {
    EXPECT_EQ(back_spheres[c].center, spheres[c].center);
    EXPECT_EQ(back_spheres[c].radius, spheres[c].radius);
    ASSERT_EQ(back[c].levels.size(), chains[c].levels.size());
    for (size_t l = 0; l < chains[c].levels.size(); ++l) {
      const LodLevel &a = chains[c].levels[l], &b = back[c].levels[l];
      EXPECT_EQ(a.mesh.positions, b.mesh.positions);
      EXPECT_EQ(a.mesh.normals, b.mesh.normals);
      EXPECT_EQ(a.mesh.colors, b.mesh.colors);
      EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
      EXPECT_EQ(a.mesh.edges, b.mesh.edges);
      EXPECT_EQ(a.mesh.edge_thickness, b.mesh.edge_thickness);
      EXPECT_EQ(a.mesh.points, b.mesh.points);
      EXPECT_EQ(a.cell_width, b.cell_width);
      EXPECT_EQ(a.max_error, b.max_error);
      EXPECT_EQ(a.method, b.method);
      EXPECT_EQ(a.bounds.center, b.bounds.center);
      EXPECT_EQ(a.bounds.radius, b.bounds.radius);
    }
  }
  SceneData back_scene;
  p.toSceneData(back_scene);
  ASSERT_EQ(back_scene.nodes.size(), s.nodes.size());
  for (size_t i = 0; i < s.nodes.size(); ++i) {
    EXPECT_EQ(back_scene.nodes[i].name, s.nodes[i].name);
    EXPECT_EQ(back_scene.nodes[i].parent, s.nodes[i].parent);
    EXPECT_EQ(back_scene.nodes[i].children, s.nodes[i].children);
    EXPECT_EQ(back_scene.nodes[i].mesh, s.nodes[i].mesh);
    EXPECT_EQ(back_scene.nodes[i].local, s.nodes[i].local);
  }
  EXPECT_EQ(back_scene.roots, s.roots);
  EXPECT_EQ(back_scene.meshes[1].name, "bump");
}

namespace {

// a loaded pack written again from its owned copies, in the order it has
std::vector<uint8_t> rewritten(const Pack& p) {
  SceneData s;
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  p.toSceneData(s);
  p.toChains(chains, spheres);
  PackWriteOptions o;
  o.optimize_order = false;  // already ordered
  for (size_t k = 0; k < p.objectCount(); ++k) {
    o.importance.push_back(p.object(k).importance);
    o.must_draw.push_back(p.object(k).must_draw);
    o.user_data.push_back(p.object(k).user_data);
  }
  std::vector<uint8_t> again;
  const Error e = writePackBytes(again, s, chains, spheres, o);
  EXPECT_TRUE(e.ok()) << e.message;
  return again;
}

}  // namespace

TEST(Pack, RewritingALoadedPackIsBitExact) {
  const std::vector<uint8_t> bytes = makePack(true);
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "mem").ok());
  EXPECT_EQ(rewritten(p), bytes);
}

TEST(Pack, PackWrittenBeforeAttributesLoadsAndRewritesToTheSameBytes) {
  // written by the version-1 writer before texture sets, tangents, skins, groups and source
  // vertices were stored (section 9)
  const std::string path = test::testDataDir() + "/pack/v1_before_attributes.slodpack";
  Pack p;
  const Error e = Pack::load(path, p);
  ASSERT_TRUE(e.ok()) << e.message;
  ASSERT_GE(p.chainCount(), 1u);
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  p.toChains(chains, spheres);
  size_t triangles = 0;
  for (const LodChain& c : chains)
    for (const LodLevel& l : c.levels) {
      EXPECT_TRUE(l.mesh.extra_uvs.empty() && l.mesh.tangents.empty() && l.mesh.joints.empty() &&
                  l.mesh.triangle_groups.empty() && l.source_vertex.empty());
      triangles += l.mesh.triangleCount();
    }
  EXPECT_GT(triangles, 0u);
  // without attributes the writer makes the bytes the writer made before section 9 existed
  EXPECT_EQ(rewritten(p), std::vector<uint8_t>(p.bytes(), p.bytes() + p.byteSize()));
}

TEST(Pack, OptimisedLevelsHoldTheSameGeometry) {
  SceneData s;
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  makeInput(s, chains, spheres);
  PackWriteStats stats;
  std::vector<uint8_t> bytes;
  ASSERT_TRUE(writePackBytes(bytes, s, chains, spheres, {}, &stats).ok());
  EXPECT_EQ(stats.bytes, bytes.size());
  EXPECT_LE(stats.acmr_after, stats.acmr_before);
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "mem").ok());
  for (size_t c = 0; c < chains.size(); ++c)
    for (size_t l = 0; l < chains[c].levels.size(); ++l) {
      const PackLevelView v = p.level(c, l);
      const Mesh& m = chains[c].levels[l].mesh;
      EXPECT_EQ(sorted(std::vector<glm::vec3>(v.positions.begin(), v.positions.end())), sorted(m.positions));
      EXPECT_EQ(v.triangles.size(), m.triangles.size());
      // every vertex of the level inside the level's sphere and the chain's sphere
      for (const glm::vec3& q : v.positions) {
        EXPECT_LE(glm::length(q - v.bounds.center), v.bounds.radius);
        EXPECT_LE(glm::length(q - p.chainSphere(c).center), p.chainSphere(c).radius);
      }
    }
}

TEST(Pack, ObjectsAndSceneComeBack) {
  const std::vector<uint8_t> bytes = makePack();
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "mem").ok());
  ASSERT_EQ(p.objectCount(), 3u);
  EXPECT_EQ(p.object(1).must_draw, true);
  EXPECT_EQ(p.object(2).user_data, 33u);
  EXPECT_EQ(p.object(2).chain, 1u);
  Scene scene;
  ASSERT_TRUE(p.toScene(scene).ok());
  ASSERT_EQ(scene.objectCount(), 3u);
  EXPECT_EQ(scene.importances()[2], 2.0f);
  EXPECT_EQ(scene.userData()[0], 11u);
  // object 2 is the bump at x + 3
  EXPECT_NEAR(scene.worldCenters()[2].x, p.chainSphere(1).center.x + 3.0f, 1e-5f);
}

TEST(Pack, TruncatedPacksAreRefusedNamingTheFile) {
  const std::vector<uint8_t> bytes = makePack();
  const std::string path = scenelod::test::scratchDir() + "/truncated.slodpack";
  for (size_t cut : {size_t(0), size_t(5), size_t(40), size_t(64), size_t(300), bytes.size() / 2, bytes.size() - 1}) {
    FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(bytes.data(), 1, cut, f);
    std::fclose(f);
    Pack p;
    const Error e = Pack::load(path, p);
    ASSERT_FALSE(e.ok()) << "cut at " << cut;
    EXPECT_NE(e.message.find(path), std::string::npos) << e.message;
    if (cut < 8) {
      EXPECT_NE(e.message.find("not a scenelod pack"), std::string::npos) << e.message;
    } else {
      EXPECT_EQ(e.status, Status::kCorrupt) << e.message;
      EXPECT_NE(e.message.find("truncated"), std::string::npos) << e.message;
    }
  }
  std::remove(path.c_str());
  Pack p;
  const Error missing = Pack::load(path, p);
  EXPECT_EQ(missing.status, Status::kIoError);
  EXPECT_NE(missing.message.find(path), std::string::npos);
}

TEST(Pack, EveryFlippedBitIsRefused) {
  const std::vector<uint8_t> bytes = makePack();
  // every bit of the header and section table, and a stride through the rest
  for (size_t bit = 0; bit < bytes.size() * 8; bit += bit < 8 * 320 ? 1 : 97) {
    std::vector<uint8_t> bad = bytes;
    bad[bit / 8] ^= uint8_t(1u << (bit % 8));
    Pack p;
    const Error e = Pack::fromBytes(bad.data(), bad.size(), p, "flipped.slodpack");
    ASSERT_FALSE(e.ok()) << "bit " << bit << " flipped and accepted";
    EXPECT_NE(e.message.find("flipped.slodpack"), std::string::npos) << e.message;
    if (bit >= 64 * 8) {
      EXPECT_EQ(e.status, Status::kCorrupt) << e.message;
      EXPECT_NE(e.message.find("checksum mismatch"), std::string::npos) << e.message;
    }
  }
}

TEST(Pack, OtherVersionsAreRefusedWithTheVersionNamed) {
  std::vector<uint8_t> bytes = makePack();
  const uint32_t v2 = 2;
  std::memcpy(bytes.data() + 8, &v2, 4);
  resign(bytes);  // a well-formed version-2 file: only the version is wrong
  Pack p;
  const Error e = Pack::fromBytes(bytes.data(), bytes.size(), p, "future.slodpack");
  EXPECT_EQ(e.status, Status::kUnsupported);
  EXPECT_NE(e.message.find("future.slodpack: pack version 2, this build reads version 1"), std::string::npos) << e.message;
}

TEST(Pack, HandMadeBadIndexIsCaughtEvenWithAValidChecksum) {
  std::vector<uint8_t> bytes = makePack(false);
  Pack good;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), good, "mem").ok());
  // overwrite the first triangle index of chain 0 level 0 with a huge value, then re-sign: the same
  // offset in `bytes` as in the loaded copy
  const size_t at = size_t(reinterpret_cast<const uint8_t*>(good.level(0, 0).triangles.data) - good.bytes());
  const uint32_t huge = 999999;
  std::memcpy(bytes.data() + at, &huge, 4);
  resign(bytes);
  Pack p;
  const Error e = Pack::fromBytes(bytes.data(), bytes.size(), p, "handmade");
  EXPECT_EQ(e.status, Status::kCorrupt);
  EXPECT_NE(e.message.find("vertex index out of range"), std::string::npos) << e.message;
  // without the index check the structure is still sound and loads
  EXPECT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "handmade", false).ok());
}

namespace {

Error parseBytes(const std::vector<uint8_t>& bytes) {
  Pack p;
  return Pack::fromBytes(bytes.data(), bytes.size(), p, "hostile.slodpack");
}

}  // namespace

TEST(Pack, SectionTableOffsetNearTwoToThe64IsRefused) {
  // a wrapping bounds check once let this read far outside a pack of 128 KiB or more
  std::vector<uint8_t> bytes = makePack();
  bytes.resize(std::max<size_t>(bytes.size(), 160 * 1024), 0);
  const uint64_t huge = ~uint64_t(0) - 15;  // 16-aligned, and huge + 8 x 32 wraps to a small number
  std::memcpy(bytes.data() + 32, &huge, 8);
  resign(bytes);
  const Error e = parseBytes(bytes);
  EXPECT_EQ(e.status, Status::kCorrupt);
  EXPECT_NE(e.message.find("hostile.slodpack: section table out of bounds"), std::string::npos) << e.message;
}

// a made pack with the 4 or 8 bytes of `value` written at `at(bytes)`, re-signed: parse must refuse
// it as corrupt with `expect` in the message
template <class T, class At>
void expectRefusedEdit(At at, T value, const std::string& expect) {
  std::vector<uint8_t> bytes = makePack();
  const size_t offset = at(bytes);
  ASSERT_NE(offset, 0u);
  std::memcpy(bytes.data() + offset, &value, sizeof value);
  resign(bytes);
  const Error e = parseBytes(bytes);
  EXPECT_EQ(e.status, Status::kCorrupt);
  EXPECT_NE(e.message.find(expect), std::string::npos) << e.message;
}

TEST(Pack, SectionOffsetNearTwoToThe64IsRefused) {
  auto first_section_offset = [](const std::vector<uint8_t>& b) {
    uint64_t table;
    std::memcpy(&table, b.data() + 32, 8);
    return size_t(table + 8);
  };
  expectRefusedEdit(first_section_offset, ~uint64_t(0) - 3, "lies outside the file");
}

TEST(Pack, ChainWithoutLevelsIsRefused) {
  // such a pack once passed `pack --check`, and a replay then culled every object
  auto chain0_level_count = [](const std::vector<uint8_t>& b) { return sectionOffset(b, 5) + 4; };
  expectRefusedEdit(chain0_level_count, uint32_t(0), "chain 0 has no levels");
}

TEST(Pack, NodeParentCycleIsRefused) {
  auto node0_parent = [](const std::vector<uint8_t>& b) { return sectionOffset(b, 1); };
  expectRefusedEdit(node0_parent, int32_t(0), "the node parents form a cycle");  // its own parent
}
