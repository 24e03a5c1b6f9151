// exportGltfLods: the input file kept, LOD levels added. Round trips of the shared models (JSON of
// materials, textures, samplers, skins, animations, cameras; image bytes; the scene and its levels
// read back), unknown extensions and extras kept, skinned levels, writing over the input, and
// refusals that write nothing.
#include <fstream>
#include <string>
#include <vector>

#include <map>

#include <gtest/gtest.h>

#include "gltf_test_support.h"

using namespace scenelod;
using namespace scenelod::scene;
using test::contains;
using test::makeDir;

namespace {

// one triangle in a data URI with a morph target, a camera, a light, extras, and an optional
// extension scenelod does not know
std::string triangleGltf(const std::string& required = "") {
  return std::string(R"({"asset":{"version":"2.0"},"extensionsUsed":["EXT_unknown_thing","KHR_lights_punctual")") +
         (required.empty() ? "" : ",\"" + required + "\"") + "]" +
         (required.empty() ? "" : ",\"extensionsRequired\":[\"" + required + "\"]") +
         R"(,"extras":{"pipeline":"test"},
    "extensions":{"KHR_lights_punctual":{"lights":[{"type":"point","color":[1,0.5,0],"intensity":2,"name":"lamp"}]}},
    "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
    "bufferViews":[{"buffer":0,"byteLength":36}],
    "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
    "materials":[{"name":"red","pbrMetallicRoughness":{"baseColorFactor":[1,0,0,1]},"extras":{"note":"kept"}}],
    "meshes":[{"name":"tri","weights":[0.5],"primitives":[{"attributes":{"POSITION":0},"material":0,"targets":[{"POSITION":0}]}]}],
    "cameras":[{"type":"perspective","perspective":{"yfov":0.8,"znear":0.1}}],
    "nodes":[{"name":"object","mesh":0,"extensions":{"EXT_unknown_thing":{"answer":42}}},{"name":"eye","camera":0,"extensions":{"KHR_lights_punctual":{"light":0}}}],
    "scenes":[{"nodes":[0,1]}],"scene":0})";
}

// the triangles a level has in a file written with prisms (the default): its own, plus 8 per thick
// edge of non-zero length and 8 per point of a level with a cell width
size_t drawnTriangles(const LodLevel& level) {
  const Mesh& m = level.mesh;
  size_t n = m.triangleCount();
  for (size_t e = 0; e < m.edgeCount(); ++e)
    if (m.edgeThickness(e) > 0.0f && m.positions[m.edges[2 * e]] != m.positions[m.edges[2 * e + 1]]) n += 8;
  if (level.cell_width > 0.0f) n += 8 * m.pointCount();
  return n;
}

std::string writeText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// a chain of the triangle: level 1 is a copy of level 0, enough to write and read back
LodChain twoLevels(const Mesh& mesh) {
  LodChain c;
  c.levels.resize(2);
  c.levels[0].mesh = mesh;
  c.levels[1].mesh = mesh;
  c.levels[1].cell_width = 0.5f;
  c.levels[1].method = LodMethod::kUniform;
  return c;
}

// exports `in` with the two-level chain of every mesh
Error exportCopies(const std::string& in, const std::string& out) {
  SceneData s;
  if (Error e = importGltf(in, s); !e.ok()) return e;
  std::vector<LodChain> chains;
  for (const MeshData& m : s.meshes) chains.push_back(twoLevels(m.mesh));
  std::vector<const LodChain*> ptrs;
  for (const LodChain& c : chains) ptrs.push_back(&c);
  return exportGltfLods(in, out, s, ptrs);
}

// `j` without the properties that equal glTF's defaults, so that two spellings of one value compare
// equal (tinygltf writes some defaults, such as a sampler's wrap modes, and drops others)
nlohmann::json withoutDefaults(nlohmann::json j) {
  static const std::vector<std::pair<const char*, nlohmann::json>> kDefaults = {
      {"emissiveFactor", {0, 0, 0}}, {"alphaMode", "OPAQUE"}, {"alphaCutoff", 0.5}, {"doubleSided", false},
      {"baseColorFactor", {1, 1, 1, 1}}, {"metallicFactor", 1}, {"roughnessFactor", 1}, {"texCoord", 0}, {"scale", 1},
      {"strength", 1}, {"wrapS", 10497}, {"wrapT", 10497}, {"interpolation", "LINEAR"}, {"mode", 4}};
  if (j.is_object()) {
    for (const auto& [key, value] : kDefaults)
      if (j.contains(key) && j[key] == value) j.erase(key);
    for (auto& [key, value] : j.items()) value = withoutDefaults(value);
  } else if (j.is_array()) {
    for (nlohmann::json& value : j) value = withoutDefaults(value);
  }
  return j;
}

// the elements of IN's array `key` are OUT's first ones, equal as JSON up to glTF's defaults
void expectKeptArray(const nlohmann::json& in, const nlohmann::json& out, const char* key) {
  SCOPED_TRACE(key);
  if (!in.contains(key)) return;
  ASSERT_TRUE(out.contains(key));
  ASSERT_GE(out[key].size(), in[key].size());
  for (size_t i = 0; i < in[key].size(); ++i) EXPECT_EQ(withoutDefaults(in[key][i]), withoutDefaults(out[key][i])) << key << " " << i;
}

}  // namespace

TEST(GltfPassThrough, KeepsUnknownExtensionsExtrasCamerasAndLevelZero) {
  const std::string dir = makeDir("pass_triangle");
  const std::string in = writeText(dir + "/tri.gltf", triangleGltf());
  const Error e = exportCopies(in, dir + "/out.glb");
  ASSERT_TRUE(e.ok()) << e.message;
  const nlohmann::json a = test::readGltfJson(in), b = test::readGltfJson(dir + "/out.glb");
  EXPECT_EQ(b["extras"], a["extras"]);
  EXPECT_EQ(b["nodes"][0]["extensions"]["EXT_unknown_thing"], a["nodes"][0]["extensions"]["EXT_unknown_thing"]);
  EXPECT_EQ(b["nodes"][0]["extensions"]["MSFT_lod"]["ids"], nlohmann::json::array({2}));
  EXPECT_EQ(b["nodes"][1], a["nodes"][1]);
  for (const char* key : {"materials", "cameras", "accessors"}) expectKeptArray(a, b, key);
  EXPECT_EQ(withoutDefaults(b["meshes"][0]), withoutDefaults(a["meshes"][0]));  // level 0 is the input mesh itself
  EXPECT_EQ(b["meshes"][1]["primitives"][0]["material"], 0);
  EXPECT_EQ(b["extensionsUsed"], nlohmann::json::array({"EXT_unknown_thing", "KHR_lights_punctual", "MSFT_lod"}));
  EXPECT_EQ(withoutDefaults(b["extensions"]), withoutDefaults(a["extensions"]));
  // the level has no morph targets, and says so
  EXPECT_FALSE(b["meshes"][1]["primitives"][0].contains("targets"));
  EXPECT_EQ(b["nodes"][2]["extras"]["scenelod"]["morph_targets"], "dropped");
  // read back: the same scene and a two-level chain
  SceneData s;
  std::vector<LodChain> chains;
  ASSERT_TRUE(importGltfLods(dir + "/out.glb", s, chains).ok());
  EXPECT_EQ(s.nodes.size(), 2u);
  ASSERT_EQ(chains.size(), 1u);
  EXPECT_EQ(chains[0].levelCount(), 2u);
}

TEST(GltfPassThrough, RefusesARequiredExtensionItCannotKeepAndWritesNothing) {
  const std::string dir = makeDir("pass_required");
  const std::string in = writeText(dir + "/tri.gltf", triangleGltf("EXT_unknown_thing"));
  const Error e = exportCopies(in, dir + "/out.glb");
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status, Status::kUnsupported);
  EXPECT_TRUE(contains(e.message, "requires extension EXT_unknown_thing")) << e.message;
  EXPECT_FALSE(test::fileExists(dir + "/out.glb"));
}

// broken references in the input: refused naming the file and the element, nothing written
TEST(GltfPassThrough, BadReferencesAreRefusedAndNothingIsWritten) {
  const std::string dir = makeDir("pass_bad_refs");
  const std::string good = triangleGltf();
  struct Case {
    const char* from;
    const char* to;
    const char* message;
  };
  const Case cases[] = {
      {R"("material":0,)", R"("material":3,)", "primitive 0: material 3 out of range"},
      {R"("materials":[{"name":"red",)", R"("materials":[{"name":"red","pbrMetallicRoughness":{"baseColorTexture":{"index":5}}},{"name":"x",)",
       "material 0: texture 5 out of range (the file has 0)"},
      {R"("materials":[{"name":"red",)",
       R"("textures":[{"source":0}],"images":[{"uri":"../outside.png"}],"materials":[{"name":"red","pbrMetallicRoughness":{"baseColorTexture":{"index":0}}},{"name":"x",)",
       "external URI '../outside.png' escapes the glTF file's folder"},
      {R"("materials":[{"name":"red",)", R"("textures":[{"source":0}],"images":[{"uri":"missing.png"}],"materials":[{"name":"red",)",
       "image 0: cannot read 'missing.png'"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.message);
    const size_t at = good.find(c.from);
    ASSERT_NE(at, std::string::npos);
    std::string edited = good;
    edited.replace(at, std::string(c.from).size(), c.to);
    const std::string in = writeText(dir + "/bad.gltf", edited), out = dir + "/out.glb";
    const Error e = exportCopies(in, out);
    ASSERT_FALSE(e.ok());
    EXPECT_TRUE(contains(e.message, in + ": ")) << e.message;
    EXPECT_TRUE(contains(e.message, c.message)) << e.message;
    EXPECT_FALSE(test::fileExists(out));
  }
}

TEST(GltfPassThrough, WritingOverTheInputGlbReplacesItOnlyOnSuccess) {
  const std::string dir = makeDir("pass_inplace");
  const std::string src = writeText(dir + "/tri.gltf", triangleGltf());
  const std::string glb = dir + "/tri.glb";
  ASSERT_TRUE(exportCopies(src, glb).ok());
  // tri.glb has levels now: building levels of it again is refused, and it is left as it was
  const std::vector<unsigned char> before = test::readFileBytes(glb);
  const Error again = exportCopies(glb, glb);
  ASSERT_FALSE(again.ok());
  EXPECT_TRUE(contains(again.message, "already has MSFT_lod")) << again.message;
  EXPECT_EQ(test::readFileBytes(glb), before);
  // a GLB without levels written over itself: the new file has them and everything else
  const std::string plain = dir + "/plain.glb";
  SceneData s;
  ASSERT_TRUE(importGltf(src, s).ok());
  ASSERT_TRUE(exportGlb(plain, s).ok());
  const Error e = exportCopies(plain, plain);
  ASSERT_TRUE(e.ok()) << e.message;
  const nlohmann::json j = test::readGltfJson(plain);
  EXPECT_TRUE(j["nodes"][0]["extensions"].contains("MSFT_lod"));
  EXPECT_EQ(j["meshes"].size(), 2u);
}

TEST(GltfPassThrough, GltfOutputNeverReplacesAFileItsInputReads) {
  const std::string dir = makeDir("pass_gltf_inplace");
  const std::string in = writeText(dir + "/tri.gltf", triangleGltf());
  const std::vector<unsigned char> before = test::readFileBytes(in);
  const Error e = exportCopies(in, in);
  ASSERT_FALSE(e.ok());
  EXPECT_TRUE(contains(e.message, "would overwrite")) << e.message;
  EXPECT_EQ(test::readFileBytes(in), before);
  // elsewhere it writes the .gltf and its .bin
  ASSERT_TRUE(exportCopies(in, dir + "/out.gltf").ok());
  EXPECT_TRUE(test::fileExists(dir + "/out.bin"));
  EXPECT_EQ(test::readGltfJson(dir + "/out.gltf")["buffers"][0]["uri"], "out.bin");
  SceneData s;
  std::vector<LodChain> chains;
  ASSERT_TRUE(importGltfLods(dir + "/out.gltf", s, chains).ok());
  EXPECT_EQ(chains[0].levelCount(), 2u);
}

TEST(GltfPassThrough, SkinnedLevelsKeepTheSkinWithoutATransform) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  const std::string in = test::sharedModelsDir() + "/Fox/Fox.glb";
  const std::string out = makeDir("pass_fox") + "/fox.glb";
  const Error e = exportCopies(in, out);  // level 1 is a copy: it has joints and weights
  ASSERT_TRUE(e.ok()) << e.message;
  const nlohmann::json j = test::readGltfJson(out);
  const nlohmann::json& ids = j["nodes"][1]["extensions"]["MSFT_lod"]["ids"];
  ASSERT_EQ(ids.size(), 1u);
  const nlohmann::json& level = j["nodes"][ids[0].get<size_t>()];
  EXPECT_EQ(level["skin"], j["nodes"][1]["skin"]);
  EXPECT_FALSE(level.contains("matrix") || level.contains("translation") || level.contains("rotation"));
  const nlohmann::json& attributes = j["meshes"][level["mesh"].get<size_t>()]["primitives"][0]["attributes"];
  EXPECT_TRUE(attributes.contains("JOINTS_0") && attributes.contains("WEIGHTS_0") && attributes.contains("TEXCOORD_0"));
}

std::map<uint32_t, size_t> trianglesPerGroup(const Mesh& m) {
  std::map<uint32_t, size_t> n;
  for (size_t t = 0; t < m.triangleCount(); ++t) ++n[m.triangleGroup(t)];
  return n;
}

// every shared model through `lods`: IN's materials, textures, samplers, skins, animations, cameras
// and root extensions come out equal as JSON, images byte for byte, and the file reads back as IN's
// scene with the levels that were built
TEST(GltfPassThrough, SharedModelsRoundTrip) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  const std::string dir = makeDir("pass_shared");
  for (const std::string& model : test::sharedGltfModels()) {
    SCOPED_TRACE(model);
    const std::string in = test::sharedModelsDir() + "/" + model;
    const std::string out = dir + "/" + model.substr(0, model.find('/')) + ".glb";
    SceneLods lods;
    const Error e = test::writeLods(in, out, 2, lods);
    ASSERT_TRUE(e.ok()) << e.message;
    const nlohmann::json a = test::readGltfJson(in), b = test::readGltfJson(out);
    for (const char* key : {"materials", "textures", "samplers", "skins", "animations", "cameras", "scenes"})
      expectKeptArray(a, b, key);
    EXPECT_EQ(a.value("extensions", nlohmann::json()), b.value("extensions", nlohmann::json()));
    SceneData sa, sb;
    ASSERT_TRUE(importGltf(in, sa).ok());
    ASSERT_TRUE(importGltf(out, sb).ok());
    ASSERT_EQ(sb.images.size(), sa.images.size());
    for (size_t i = 0; i < sa.images.size(); ++i) EXPECT_EQ(sb.images[i].encoded, sa.images[i].encoded) << "image " << i;
    ASSERT_EQ(sb.skins.size(), sa.skins.size());
    for (size_t k = 0; k < sa.skins.size(); ++k) EXPECT_EQ(sb.skins[k].inverse_bind, sa.skins[k].inverse_bind);
    ASSERT_EQ(sb.animations.size(), sa.animations.size());
    for (size_t k = 0; k < sa.animations.size(); ++k)
      for (size_t i = 0; i < sa.animations[k].samplers.size(); ++i)
        EXPECT_EQ(sb.animations[k].samplers[i].values, sa.animations[k].samplers[i].values);
    SceneData back;
    std::vector<LodChain> chains;
    ASSERT_TRUE(importGltfLods(out, back, chains).ok());
    ASSERT_EQ(back.nodes.size(), sa.nodes.size());
    ASSERT_EQ(chains.size(), sa.meshes.size());
    for (size_t m = 0; m < chains.size(); ++m) {
      ASSERT_EQ(chains[m].levelCount(), lods.chains[m].levelCount()) << "mesh " << m;
      EXPECT_EQ(chains[m].levels[0].mesh.positions, sa.meshes[m].mesh.positions) << "mesh " << m;
      for (size_t l = 1; l < chains[m].levelCount(); ++l) {
        const Mesh& built = lods.chains[m].levels[l].mesh;
        EXPECT_EQ(chains[m].levels[l].mesh.triangleCount(), drawnTriangles(lods.chains[m].levels[l]));
        // read back, a level's groups are level 0's primitives again (prisms aside: they add triangles)
        if (built.edges.empty() && built.points.empty())
          EXPECT_EQ(trianglesPerGroup(chains[m].levels[l].mesh), trianglesPerGroup(built)) << "mesh " << m << " level " << l;
      }
    }
  }
}

// the Fox's levels from buildLods carry weights: every level node keeps the skin, and every
// primitive of its mesh (thick lines with their own vertices included, written as lines) has
// JOINTS_0 and WEIGHTS_0
TEST(GltfPassThrough, EveryPrimitiveOfASkinnedLevelIsSkinned) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  const std::string out = makeDir("pass_fox_levels") + "/fox.glb";
  SceneLods lods;
  const Error e = test::writeLods(test::sharedModelsDir() + "/Fox/Fox.glb", out, 8, lods, ThickEdges::kLines);
  ASSERT_TRUE(e.ok()) << e.message;
  const nlohmann::json j = test::readGltfJson(out);
  const nlohmann::json& ids = j["nodes"][1]["extensions"]["MSFT_lod"]["ids"];
  ASSERT_EQ(ids.size(), lods.chains[0].levelCount() - 1);
  size_t primitives = 0;
  for (const nlohmann::json& id : ids) {
    const nlohmann::json& node = j["nodes"][id.get<size_t>()];
    EXPECT_EQ(node["skin"], 0);
    for (const nlohmann::json& p : j["meshes"][node["mesh"].get<size_t>()]["primitives"]) {
      EXPECT_TRUE(p["attributes"].contains("JOINTS_0") && p["attributes"].contains("WEIGHTS_0")) << node["name"];
      ++primitives;
    }
  }
  EXPECT_GT(primitives, ids.size());  // some levels have thick lines or points beside their triangles
}

// the Fox's thin legs become thick edges at its coarser levels: written as prisms (the default) no
// level has LINES and each edge adds 8 triangles; written as lines they stay LINES
TEST(GltfPassThrough, ThickEdgesArePrismsUnlessLinesAreAskedFor) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  const std::string in = test::sharedModelsDir() + "/Fox/Fox.glb";
  SceneData s;
  ASSERT_TRUE(importGltf(in, s).ok());
  LodBuildParams params;
  params.chain.level_count = 8;
  SceneLods lods;
  ASSERT_TRUE(buildLods(s, params, lods, nullptr, in).ok());
  const std::vector<const LodChain*> chains{&lods.chains[0]};
  size_t edges = 0;
  for (const LodLevel& level : lods.chains[0].levels) edges += level.mesh.edgeCount();
  ASSERT_GT(edges, 0u) << "the Fox's levels should have thick edges";
  const std::string dir = makeDir("pass_prisms");
  for (ThickEdges mode : {ThickEdges::kPrisms, ThickEdges::kLines}) {
    const std::string out = dir + (mode == ThickEdges::kPrisms ? "/prisms.glb" : "/lines.glb");
    std::vector<std::string> notes;
    ASSERT_TRUE(exportGltfLods(in, out, s, chains, &notes, mode).ok());
    size_t lines = 0;
    const nlohmann::json j = test::readGltfJson(out);
    for (size_t m = 1; m < j["meshes"].size(); ++m)
      for (const nlohmann::json& p : j["meshes"][m]["primitives"]) lines += p.value("mode", 4) == 1;
    SceneData back;
    std::vector<LodChain> read;
    ASSERT_TRUE(importGltfLods(out, back, read).ok());
    ASSERT_EQ(read.size(), 1u);
    ASSERT_EQ(read[0].levelCount(), lods.chains[0].levelCount());
    if (mode == ThickEdges::kPrisms) {
      EXPECT_EQ(lines, 0u);
      EXPECT_FALSE(notes.empty());  // the triangles the prisms add, per level
      for (size_t l = 1; l < read[0].levelCount(); ++l) {
        EXPECT_EQ(read[0].levels[l].mesh.triangleCount(), drawnTriangles(lods.chains[0].levels[l])) << "level " << l;
        EXPECT_EQ(read[0].levels[l].mesh.edgeCount(), 0u) << "level " << l;
      }
    } else {
      EXPECT_GT(lines, 0u);
      for (size_t l = 1; l < read[0].levelCount(); ++l)
        EXPECT_EQ(read[0].levels[l].mesh.edgeCount(), lods.chains[0].levels[l].mesh.edgeCount()) << "level " << l;
    }
  }
}
