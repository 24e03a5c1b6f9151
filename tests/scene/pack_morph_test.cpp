// Geomorph targets in LOD packs (section 11): round trips with and without vertex reordering, packs
// written before the section, and hand-edited or hostile records.
#include <algorithm>
#include <cstring>
#include <set>
#include <tuple>

#include <gtest/gtest.h>

#include "scenelod/lodcore/chain.h"
#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/pack.h"
#include "pack_bytes.h"
#include "test_support.h"

using namespace scenelod;
using namespace scenelod::scene;
using scenelod::test::resign;
using scenelod::test::sectionEntry;

namespace {

// a bumpy textured grid, its chain with geomorphs, in a one-object scene
struct MorphInput {
  SceneData scene;
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;

  MorphInput() {
    Mesh m;
    const uint32_t n = 24;
    for (uint32_t y = 0; y <= n; ++y)
      for (uint32_t x = 0; x <= n; ++x) {
        m.positions.push_back({float(x) / n, float(y) / n, 0.05f * float((x * 7 + y * 3) % 5)});
        m.uvs.push_back({float(x) / n, float(y) / n});
        m.colors.push_back({float(x) / n, 0.5f, float(y) / n});
      }
    for (uint32_t y = 0; y < n; ++y)
      for (uint32_t x = 0; x < n; ++x) {
        const uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
        m.triangles.insert(m.triangles.end(), {a, b, d, a, d, c});
      }
    scene.meshes.resize(1);
    scene.meshes[0].name = "grid";
    scene.meshes[0].mesh = m;
    scene.nodes.resize(1);
    scene.nodes[0].mesh = 0;
    scene.roots = {0};
    chains.resize(1);
    ChainParams cp;
    cp.level_count = 4;
    EXPECT_TRUE(buildChain(m, cp, chains[0]).ok());
    spheres = {computeChainBounds(chains[0])};
  }
};

std::vector<uint8_t> write(const MorphInput& in, bool optimize, size_t max_levels = 0) {
  PackWriteOptions o;
  o.optimize_order = optimize;
  o.max_levels = max_levels;
  std::vector<uint8_t> bytes;
  const Error e = writePackBytes(bytes, in.scene, in.chains, in.spheres, o);
  EXPECT_TRUE(e.ok()) << e.message;
  return bytes;
}

Error parse(const std::vector<uint8_t>& bytes) {
  Pack p;
  return Pack::fromBytes(bytes.data(), bytes.size(), p, "morphs.slodpack");
}

// per vertex: (position, target position, target uv, target colour), to compare reordered levels
using VertexTarget = std::tuple<float, float, float, float, float, float, float, float, float>;
std::multiset<VertexTarget> targets(const LodLevel& l) {
  std::multiset<VertexTarget> set;
  for (size_t v = 0; v < l.mesh.vertexCount(); ++v) {
    const glm::vec3 p = l.mesh.positions[v], t = l.morph.positions[v];
    set.insert({p.x, p.y, p.z, t.x, t.y, t.z, l.morph.uvs[v].x, l.morph.uvs[v].y, l.morph.colors[v].x});
  }
  return set;
}

}  // namespace

TEST(PackMorph, UnoptimisedRoundTripKeepsEveryTarget) {
  const MorphInput in;
  ASSERT_GE(in.chains[0].levelCount(), 4u);
  const std::vector<uint8_t> bytes = write(in, false);
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "mem").ok());
  std::vector<LodChain> back;
  std::vector<Sphere> spheres;
  p.toChains(back, spheres);
  ASSERT_EQ(back[0].levelCount(), in.chains[0].levelCount());
  for (size_t l = 0; l < back[0].levelCount(); ++l) {
    const LevelMorph& a = in.chains[0].levels[l].morph;
    const LevelMorph& b = back[0].levels[l].morph;
    EXPECT_EQ(a.positions, b.positions) << "level " << l;
    EXPECT_EQ(a.normals, b.normals) << "level " << l;
    EXPECT_EQ(a.colors, b.colors) << "level " << l;
    EXPECT_EQ(a.uvs, b.uvs) << "level " << l;
    EXPECT_EQ(a.tangents, b.tangents) << "level " << l;
    EXPECT_EQ(b.empty(), l + 1 == back[0].levelCount()) << "level " << l;
  }
  EXPECT_EQ(p.levelMorph(0, 0).positions.size(), in.chains[0].levels[0].mesh.vertexCount());
  // a loaded pack written again gives the same bytes
  SceneData scene;
  p.toSceneData(scene);
  std::vector<uint8_t> again;
  PackWriteOptions o;
  o.optimize_order = false;
  ASSERT_TRUE(writePackBytes(again, scene, back, spheres, o).ok());
  EXPECT_EQ(again, bytes);
}

TEST(PackMorph, ReorderedLevelsKeepEachVertexsTarget) {
  const MorphInput in;
  const std::vector<uint8_t> bytes = write(in, true);
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "mem").ok());
  std::vector<LodChain> back;
  std::vector<Sphere> spheres;
  p.toChains(back, spheres);
  for (size_t l = 0; l + 1 < back[0].levelCount(); ++l) {
    EXPECT_NE(back[0].levels[l].mesh.positions, in.chains[0].levels[l].mesh.positions) << "level " << l << " not reordered";
    EXPECT_EQ(targets(back[0].levels[l]), targets(in.chains[0].levels[l])) << "level " << l;
  }
}

TEST(PackMorph, TruncatedChainsKeepNoTargetsIntoLevelsNotWritten) {
  const MorphInput in;
  const std::vector<uint8_t> bytes = write(in, false, 2);
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "mem").ok());
  ASSERT_EQ(p.levelCount(0), 2u);
  EXPECT_FALSE(p.levelMorph(0, 0).positions.empty());
  EXPECT_TRUE(p.levelMorph(0, 1).positions.empty());
}

TEST(PackMorph, ChainsWithoutTargetsWriteNoSectionAndOldPacksLoad) {
  MorphInput in;
  for (LodLevel& l : in.chains[0].levels) l.morph = LevelMorph();
  const std::vector<uint8_t> bytes = write(in, true);
  EXPECT_EQ(sectionEntry(bytes, 11), 0u);
  // written before section 11 (and section 9) existed
  Pack old;
  const Error e = Pack::load(test::testDataDir() + "/pack/v1_before_attributes.slodpack", old);
  ASSERT_TRUE(e.ok()) << e.message;
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  old.toChains(chains, spheres);
  for (const LodChain& c : chains)
    for (const LodLevel& l : c.levels) EXPECT_TRUE(l.morph.empty());
}

TEST(PackMorph, WriterRefusesTargetsThatAreNotOnePerVertex) {
  MorphInput in;
  in.chains[0].levels[1].morph.uvs.pop_back();
  std::vector<uint8_t> bytes;
  const Error e = writePackBytes(bytes, in.scene, in.chains, in.spheres, PackWriteOptions{});
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("level 1: its geomorph targets are not one per vertex"), std::string::npos) << e.message;
}

TEST(PackMorph, TruncatedOrHostileMorphSectionsAreRefusedByName) {
  const MorphInput in;
  const std::vector<uint8_t> bytes = write(in, false);
  ASSERT_TRUE(parse(bytes).ok());
  const size_t entry = sectionEntry(bytes, 11);
  ASSERT_NE(entry, 0u);
  uint64_t section, count;
  std::memcpy(&section, bytes.data() + entry + 8, 8);
  std::memcpy(&count, bytes.data() + entry + 16, 8);
  ASSERT_EQ(count, in.chains[0].levelCount());
  auto expectRefused = [&](std::vector<uint8_t> b, const std::string& words) {
    resign(b);
    const Error e = parse(b);
    EXPECT_EQ(e.status, Status::kCorrupt) << words;
    EXPECT_NE(e.message.find("morphs.slodpack"), std::string::npos) << e.message;
    EXPECT_NE(e.message.find(words), std::string::npos) << e.message;
  };
  {  // a section cut short: one record fewer than level records
    std::vector<uint8_t> b = bytes;
    const uint64_t fewer = count - 1;
    std::memcpy(b.data() + entry + 16, &fewer, 8);
    expectRefused(b, "section 11 (geomorphs) has " + std::to_string(fewer) + " level morph records for " +
                         std::to_string(count) + " level records");
  }
  {  // a section running past the end of the file
    std::vector<uint8_t> b = bytes;
    const uint64_t huge = uint64_t(1) << 40;
    std::memcpy(b.data() + entry + 16, &huge, 8);
    expectRefused(b, "section 11 lies outside the file");
  }
  {  // a file cut inside the section (checksum and size no longer match)
    std::vector<uint8_t> b(bytes.begin(), bytes.begin() + std::ptrdiff_t(section + 40));
    const Error e = parse(b);
    EXPECT_EQ(e.status, Status::kCorrupt);
    EXPECT_NE(e.message.find("truncated"), std::string::npos) << e.message;
  }
  // record 1 (level 1): vertex count, then the positions offset
  const size_t record = size_t(section) + 80;
  {
    std::vector<uint8_t> b = bytes;
    const uint32_t wrong = 7;
    std::memcpy(b.data() + record, &wrong, 4);
    expectRefused(b, "level record 1 has geomorph targets for 7 vertices");
  }
  {
    std::vector<uint8_t> b = bytes;
    const uint64_t outside = b.size() - 8;
    std::memcpy(b.data() + record + 16, &outside, 8);
    expectRefused(b, "level record 1 has a geomorph array outside the data section");
  }
  {
    std::vector<uint8_t> b = bytes;
    const uint64_t none = 0;
    std::memcpy(b.data() + record + 16, &none, 8);
    expectRefused(b, "level record 1 has geomorph targets without positions");
  }
}
