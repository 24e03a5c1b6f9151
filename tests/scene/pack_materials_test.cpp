// The materials and level groups sections of LOD packs: each level's triangle, edge and point groups
// come back with their materials (material ranges an engine can draw), on a made scene and on the
// shared textured models; hand-edited group materials are refused. (Packs written before these
// sections: pack_test.cpp.)
#include <cstring>
#include <map>

#include <gtest/gtest.h>

#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/lod_build.h"
#include "scenelod/scene/pack.h"
#include "test_support.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

// a strip of 2n quads along x: the left half material 1's primitive (group 0), the right half
// material 0's (group 1), plus two edges (group 1, group 0) and a point (group 1)
Mesh twoPrimitiveStrip(uint32_t n) {
  Mesh m;
  for (uint32_t x = 0; x <= 2 * n; ++x) {
    m.positions.push_back({float(x), 0.0f, 0.0f});
    m.positions.push_back({float(x), 1.0f, 0.0f});
  }
  for (uint32_t x = 0; x < 2 * n; ++x) {
    const uint32_t a = 2 * x, b = a + 1, c = a + 2, d = a + 3;
    // interleaved groups in the input: the writer's reordering must sort them into runs
    m.triangles.insert(m.triangles.end(), {a, c, d, a, d, b});
    const uint32_t g = x < n ? 0u : 1u;
    m.triangle_groups.insert(m.triangle_groups.end(), {g, g});
  }
  const uint32_t top = 2 * (2 * n) + 1;
  m.positions.push_back({0.0f, 2.0f, 0.0f});
  m.positions.push_back({1.0f, 2.0f, 0.0f});
  m.positions.push_back({2.0f, 2.0f, 0.0f});
  m.edges = {top + 1, top + 2, top + 2, top + 3};
  m.edge_thickness = {0.1f, 0.2f};
  m.edge_groups = {1, 0};
  m.points = {top + 3};
  m.point_groups = {1};
  return m;
}

void makeMaterialInput(SceneData& s, std::vector<LodChain>& chains, std::vector<Sphere>& spheres) {
  s = SceneData{};
  s.materials.resize(2);
  s.materials[0].name = "paint";
  s.materials[0].base_color = {0.8f, 0.1f, 0.1f, 1.0f};
  s.materials[1].name = "label";
  s.materials[1].textured = true;
  s.materials[1].average_texel_color = {0.25f, 0.5f, 0.75f};
  s.materials[1].base_color_texcoord = 1;
  s.materials[1].base_color_transform.offset = {0.5f, 0.25f};
  s.materials[1].base_color_transform.rotation = 0.5f;
  s.materials[1].base_color_transform.scale = {2.0f, 3.0f};
  s.meshes.resize(1);
  s.meshes[0].name = "sign";
  s.meshes[0].mesh = twoPrimitiveStrip(4);
  s.meshes[0].primitive_materials = {1, 0};
  s.nodes.resize(1);
  s.nodes[0].mesh = 0;
  s.roots = {0};
  chains.assign(1, LodChain{});
  LodLevel l0;
  l0.mesh = s.meshes[0].mesh;
  chains[0].levels.push_back(l0);
  LodLevel l1;
  l1.mesh = twoPrimitiveStrip(2);
  l1.cell_width = 1.0f;
  l1.method = LodMethod::kFloatingHeaviest;
  chains[0].levels.push_back(l1);
  spheres = {computeChainBounds(chains[0])};
}

std::vector<uint8_t> materialPack(bool optimize, const std::string& source = "sign.glb") {
  SceneData s;
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  makeMaterialInput(s, chains, spheres);
  PackWriteOptions o;
  o.optimize_order = optimize;
  o.material_source = source;
  std::vector<uint8_t> bytes;
  const Error e = writePackBytes(bytes, s, chains, spheres, o);
  EXPECT_TRUE(e.ok()) << e.message;
  return bytes;
}

// triangles per material over a level, from its ranges
std::map<int32_t, uint32_t> trianglesPerMaterial(const PackLevelView& v) {
  std::map<int32_t, uint32_t> n;
  uint32_t next = 0;
  for (const PackMaterialRange& r : materialRanges(v)) {
    EXPECT_EQ(r.first_triangle, next);  // ranges tile the level in order
    next += r.triangle_count;
    n[r.material] += r.triangle_count;
  }
  EXPECT_EQ(next, v.triangles.size() / 3);
  return n;
}

}  // namespace

TEST(PackMaterials, MaterialsAndTheirSourceComeBack) {
  const std::vector<uint8_t> bytes = materialPack(true);
  Pack p;
  const Error e = Pack::fromBytes(bytes.data(), bytes.size(), p, "mem");
  ASSERT_TRUE(e.ok()) << e.message;
  ASSERT_EQ(p.materialCount(), 2u);
  EXPECT_STREQ(p.material(0).name, "paint");
  EXPECT_STREQ(p.material(1).name, "label");
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_STREQ(p.material(i).source, "sign.glb");
    EXPECT_EQ(p.material(i).source_index, int32_t(i));
  }
  EXPECT_EQ(p.material(0).base_color, glm::vec4(0.8f, 0.1f, 0.1f, 1.0f));
  EXPECT_FALSE(p.material(0).textured);
  const PackMaterialView label = p.material(1);
  EXPECT_TRUE(label.textured);
  EXPECT_EQ(label.average_texel_color, glm::vec3(0.25f, 0.5f, 0.75f));
  EXPECT_EQ(label.base_color_texcoord, 1u);
  EXPECT_EQ(label.base_color_transform.offset, glm::vec2(0.5f, 0.25f));
  EXPECT_EQ(label.base_color_transform.rotation, 0.5f);
  EXPECT_EQ(label.base_color_transform.scale, glm::vec2(2.0f, 3.0f));
}

TEST(PackMaterials, EveryLevelGivesOneRangePerMaterialWithItsTriangles) {
  const std::vector<uint8_t> bytes = materialPack(true);
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "mem").ok());
  // level 0: 8 quads, 4 per primitive; level 1: 4 quads, 2 per primitive
  const uint32_t per_material[2] = {8, 4};
  for (size_t l = 0; l < 2; ++l) {
    const PackLevelView v = p.level(0, l);
    ASSERT_EQ(v.group_materials.size(), 2u);
    EXPECT_EQ(v.group_materials[0], 1);
    EXPECT_EQ(v.group_materials[1], 0);
    EXPECT_EQ(materialRanges(v).size(), 2u) << "level " << l << ": the writer sorts triangles by group";
    const std::map<int32_t, uint32_t> n = trianglesPerMaterial(v);
    EXPECT_EQ(n.at(0), per_material[l]);
    EXPECT_EQ(n.at(1), per_material[l]);
    // edges and points keep their groups (edges are not reordered)
    ASSERT_EQ(v.edge_groups.size(), 2u);
    EXPECT_EQ(v.edge_groups[0], 1u);
    EXPECT_EQ(v.edge_groups[1], 0u);
    ASSERT_EQ(v.point_groups.size(), 1u);
    EXPECT_EQ(v.point_groups[0], 1u);
  }
}

TEST(PackMaterials, UnorderedPacksGiveRunsThatStillTileTheLevel) {
  const std::vector<uint8_t> bytes = materialPack(false);
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "mem").ok());
  const PackLevelView v = p.level(0, 0);
  const std::map<int32_t, uint32_t> n = trianglesPerMaterial(v);
  EXPECT_EQ(n.at(0), 8u);
  EXPECT_EQ(n.at(1), 8u);
}

TEST(PackMaterials, SceneDataAndChainsComeBackAndRewriteToTheSameBytes) {
  const std::vector<uint8_t> bytes = materialPack(true);
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "mem").ok());
  SceneData s;
  p.toSceneData(s);
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_EQ(s.materials[1].name, "label");
  EXPECT_EQ(s.materials[1].base_color_texture, -1);  // the textures stay in the source file
  EXPECT_EQ(s.meshes[0].primitive_materials, (std::vector<int32_t>{1, 0}));
  EXPECT_EQ(s.meshes[0].mesh.edge_groups, (std::vector<uint32_t>{1, 0}));
  // a vertex-colour consumer can bake the materials from the pack alone
  const std::vector<glm::vec3> baked = bakedMaterialColors(s, s.meshes[0]);
  ASSERT_EQ(baked.size(), s.meshes[0].mesh.vertexCount());
  const Mesh& m = s.meshes[0].mesh;
  EXPECT_EQ(baked[m.points[0]], glm::vec3(0.8f, 0.1f, 0.1f));  // the point is in group 1: "paint"
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  p.toChains(chains, spheres);
  ASSERT_EQ(chains[0].levelCount(), 2u);
  EXPECT_EQ(chains[0].levels[1].mesh.point_groups, (std::vector<uint32_t>{1}));
  PackWriteOptions o;
  o.optimize_order = false;
  o.material_source = "sign.glb";
  std::vector<uint8_t> again;
  ASSERT_TRUE(writePackBytes(again, s, chains, spheres, o).ok());
  EXPECT_EQ(again, bytes);
}

TEST(PackMaterials, ScenesWithoutMaterialsOrGroupsWriteNeitherSection) {
  SceneData s;
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  makeMaterialInput(s, chains, spheres);
  s.materials.clear();
  s.meshes[0].primitive_materials.clear();
  for (LodLevel& l : chains[0].levels) {
    l.mesh.edge_groups.clear();
    l.mesh.point_groups.clear();
  }
  std::vector<uint8_t> bytes;
  ASSERT_TRUE(writePackBytes(bytes, s, chains, spheres).ok());
  uint32_t section_count;
  std::memcpy(&section_count, bytes.data() + 28, 4);
  EXPECT_EQ(section_count, 9u);  // the 8 required and the level attributes (triangle groups)
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "mem").ok());
  EXPECT_EQ(p.materialCount(), 0u);
  EXPECT_TRUE(p.level(0, 0).group_materials.empty());
  // every run then has no material
  for (const PackMaterialRange& r : materialRanges(p.level(0, 0))) EXPECT_EQ(r.material, -1);
}

TEST(PackMaterials, AMaterialIndexPastTheScenesMaterialsIsRefusedOnWrite) {
  SceneData s;
  std::vector<LodChain> chains;
  std::vector<Sphere> spheres;
  makeMaterialInput(s, chains, spheres);
  s.meshes[0].primitive_materials = {1, 2};
  std::vector<uint8_t> bytes;
  const Error e = writePackBytes(bytes, s, chains, spheres, {}, nullptr, "out.slodpack");
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_NE(e.message.find("out.slodpack mesh 0 'sign': material 2 out of range"), std::string::npos) << e.message;
}

TEST(PackMaterials, AHandEditedGroupMaterialIsRefusedNamingTheLevel) {
  std::vector<uint8_t> bytes = materialPack(true);
  // the group materials array of level record 0, from its level groups record (section 12)
  uint32_t count;
  uint64_t table;
  std::memcpy(&count, bytes.data() + 28, 4);
  std::memcpy(&table, bytes.data() + 32, 8);
  uint64_t groups = 0;
  for (uint32_t s = 0; s < count; ++s) {
    uint32_t kind;
    std::memcpy(&kind, bytes.data() + table + 32 * s, 4);
    if (kind == 12) std::memcpy(&groups, bytes.data() + table + 32 * s + 8, 8);
  }
  ASSERT_NE(groups, 0u) << "no level groups section";
  uint64_t group_materials;
  std::memcpy(&group_materials, bytes.data() + groups + 8, 8);
  const int32_t bad = 7;
  std::memcpy(bytes.data() + group_materials, &bad, 4);
  // re-sign, so that only the edit is wrong
  std::memset(bytes.data() + 24, 0, 4);
  const uint32_t crc = crc32(bytes.data(), bytes.size());
  std::memcpy(bytes.data() + 24, &crc, 4);
  Pack p;
  const Error e = Pack::fromBytes(bytes.data(), bytes.size(), p, "hostile.slodpack");
  EXPECT_EQ(e.status, Status::kCorrupt);
  EXPECT_NE(e.message.find("hostile.slodpack: level record 0 has group 0 with material 7 but the pack has 2 materials"),
            std::string::npos)
      << e.message;
}

TEST(PackMaterials, SheenChairLevelsKeepTheirMaterialRangesThroughAPack) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  const std::string path = test::sharedModelsDir() + "/SheenChair/SheenChair.gltf";
  SceneData s;
  const Error le = loadScene(path, s);
  ASSERT_TRUE(le.ok()) << le.message;
  LodBuildParams params;
  params.chain.level_count = 4;
  SceneLods lods;
  ASSERT_TRUE(buildLods(s, params, lods, nullptr, path).ok());
  PackWriteOptions o;
  o.material_source = "SheenChair.gltf";
  std::vector<uint8_t> bytes;
  ASSERT_TRUE(writePackBytes(bytes, s, lods.chains, lods.chain_spheres, o).ok());
  Pack p;
  ASSERT_TRUE(Pack::fromBytes(bytes.data(), bytes.size(), p, "chair").ok());
  ASSERT_EQ(p.materialCount(), s.materials.size());
  for (size_t i = 0; i < s.materials.size(); ++i) EXPECT_EQ(std::string(p.material(i).name), s.materials[i].name);
  size_t levels_checked = 0;
  for (size_t c = 0; c < p.chainCount(); ++c)
    for (size_t l = 0; l < p.levelCount(c); ++l) {
      // each material's triangles in the pack equal the chain level's, counted from its groups
      const Mesh& m = lods.chains[c].levels[l].mesh;
      std::map<int32_t, uint32_t> expected;
      for (size_t t = 0; t < m.triangleCount(); ++t) {
        const uint32_t g = m.triangleGroup(t);
        const std::vector<int32_t>& pm = s.meshes[c].primitive_materials;
        ++expected[g < pm.size() ? pm[g] : -1];
      }
      const PackLevelView v = p.level(c, l);
      EXPECT_EQ(trianglesPerMaterial(v), expected) << "chain " << c << " level " << l;
      EXPECT_EQ(materialRanges(v).size(), expected.size()) << "chain " << c << " level " << l;
      ++levels_checked;
    }
  EXPECT_GE(levels_checked, 8u);
}
