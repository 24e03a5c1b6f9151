#include "scenelod/scene/gltf_io.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include <sys/stat.h>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "scenelod/lodcore/obj_io.h"
#include "gltf_test_support.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

using test::contains;
using test::makeDir;

void writeBytes(const std::string& path, const std::vector<unsigned char>& bytes) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}
void writeText(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }
std::vector<unsigned char> readBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<unsigned char>(std::istreambuf_iterator<char>(f), {});
}

struct Bin {
  std::vector<unsigned char> bytes;
  size_t add(const void* p, size_t n) {
    while (bytes.size() % 4) bytes.push_back(0);
    const size_t off = bytes.size();
    bytes.insert(bytes.end(), static_cast<const unsigned char*>(p), static_cast<const unsigned char*>(p) + n);
    return off;
  }
};

std::string replaceAll(std::string s, const std::string& from, const std::string& to) {
  for (size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size())) s.replace(p, from.size(), to);
  return s;
}

// a unit square (4 vertices, 2 triangles) in an external .bin; tokens let each test break one thing
struct SquareGltf {
  std::string uri = "square.bin";
  std::string byte_length = "60";
  std::string pos_count = "4";
  std::string indices = "1";
  std::string mode = "4";
  std::string extra = "";
  std::string primitive_extra = "";
  std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  std::vector<uint16_t> index_data = {0, 1, 2, 1, 3, 2};

  // writes folder/name and folder/square.bin; returns the .gltf path
  std::string write(const std::string& folder, const std::string& name = "square.gltf") const {
    Bin bin;
    bin.add(positions.data(), positions.size() * 4);
    bin.add(index_data.data(), index_data.size() * 2);
    writeBytes(folder + "/square.bin", bin.bytes);
    std::string json = R"({"asset":{"version":"2.0"}@EXTRA@,
      "buffers":[{"uri":"@URI@","byteLength":@LEN@}],
      "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":@POSCOUNT@,"type":"VEC3"},
                   {"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}],
      "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":@INDICES@,"mode":@MODE@ @PRIMEXTRA@}]}],
      "nodes":[{"mesh":0}],
      "scenes":[{"nodes":[0]}],"scene":0})";
    json = replaceAll(json, "@EXTRA@", extra);
    json = replaceAll(json, "@URI@", uri);
    json = replaceAll(json, "@LEN@", byte_length);
    json = replaceAll(json, "@POSCOUNT@", pos_count);
    json = replaceAll(json, "@INDICES@", indices);
    json = replaceAll(json, "@MODE@", mode);
    json = replaceAll(json, "@PRIMEXTRA@", primitive_extra);
    writeText(folder + "/" + name, json);
    return folder + "/" + name;
  }
};

Error importExpectingError(const std::string& path) {
  SceneData s;
  return importGltf(path, s);
}

}  // namespace

TEST(GltfImport, ReadsAnExternalBufferSquare) {
  const std::string path = SquareGltf().write(makeDir("square_ok"));
  SceneData s;
  const Error e = importGltf(path, s);
  ASSERT_TRUE(e.ok()) << e.message;
  ASSERT_EQ(s.nodes.size(), 1u);
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_EQ(s.roots, (std::vector<int32_t>{0}));
  const Mesh& m = s.meshes[0].mesh;
  EXPECT_EQ(m.positions, (std::vector<glm::vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}));
  EXPECT_EQ(m.triangles, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2}));
  EXPECT_TRUE(m.colors.empty());  // no material, no COLOR_0
  EXPECT_EQ(s.meshes[0].primitive_materials, (std::vector<int32_t>{-1}));
}

TEST(GltfImport, ReadsAnEmbeddedDataUriBuffer) {
  const std::string dir = makeDir("datauri");
  SquareGltf g;
  g.write(dir);
  const std::vector<unsigned char> bin = readBytes(dir + "/square.bin");
  static const char kB64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string b64;
  for (size_t i = 0; i < bin.size(); i += 3) {
    const uint32_t v = (uint32_t(bin[i]) << 16) | (i + 1 < bin.size() ? uint32_t(bin[i + 1]) << 8 : 0u) |
                       (i + 2 < bin.size() ? uint32_t(bin[i + 2]) : 0u);
    b64 += kB64[(v >> 18) & 63];
    b64 += kB64[(v >> 12) & 63];
    b64 += i + 1 < bin.size() ? kB64[(v >> 6) & 63] : '=';
    b64 += i + 2 < bin.size() ? kB64[v & 63] : '=';
  }
  g.uri = "data:application/octet-stream;base64," + b64;
  const std::string path = g.write(dir, "embedded.gltf");
  ::remove((dir + "/square.bin").c_str());  // only the data URI can provide the bytes now
  SceneData s;
  const Error e = importGltf(path, s);
  ASSERT_TRUE(e.ok()) << e.message;
  EXPECT_EQ(s.meshes[0].mesh.triangles, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2}));
  EXPECT_EQ(s.meshes[0].mesh.positions[3], glm::vec3(1, 1, 0));
}

TEST(GltfImport, ConvertsStripsFansLineStripsLoopsAndPoints) {
  const std::string dir = makeDir("modes");
  struct Case {
    int mode;
    std::vector<uint32_t> triangles, edges, points;
  };
  // indices 0 1 2 1 3 2 read as each mode
  const Case cases[] = {
      {5, {0, 1, 2, 1, 1, 2, 2, 1, 3, 1, 2, 3}, {}, {}},  // strip: odd i gives (i, i+2, i+1)
      {6, {1, 2, 0, 2, 1, 0, 1, 3, 0, 3, 2, 0}, {}, {}},  // fan around index 0
      {3, {}, {0, 1, 1, 2, 2, 1, 1, 3, 3, 2}, {}},        // line strip
      {2, {}, {0, 1, 1, 2, 2, 1, 1, 3, 3, 2, 2, 0}, {}},  // line loop closes back to the first
      {1, {}, {0, 1, 2, 1, 3, 2}, {}},                    // lines
      {0, {}, {}, {0, 1, 2, 1, 3, 2}},                    // points
  };
  for (const Case& c : cases) {
    SquareGltf g;
    g.mode = std::to_string(c.mode);
    SceneData s;
    const Error e = importGltf(g.write(dir), s);
    ASSERT_TRUE(e.ok()) << e.message;
    const Mesh& m = s.meshes[0].mesh;
    EXPECT_EQ(m.triangles, c.triangles) << "mode " << c.mode;
    EXPECT_EQ(m.edges, c.edges) << "mode " << c.mode;
    EXPECT_EQ(m.points, c.points) << "mode " << c.mode;
  }
}

TEST(GltfImport, LinePrimitivesSharingVerticesKeepTheirOwnThickness) {
  // two LINES primitives on the same POSITION accessor, each with its own _THICKNESS
  const std::string dir = makeDir("thick");
  Bin bin;
  const float pos[] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  const uint16_t idx_a[] = {0, 1}, idx_b[] = {1, 2};
  const float thick_a[] = {0.5f, 0.5f, 0.0f}, thick_b[] = {0.0f, 0.25f, 0.75f};
  const size_t o0 = bin.add(pos, sizeof(pos)), o1 = bin.add(idx_a, 4), o2 = bin.add(idx_b, 4), o3 = bin.add(thick_a, 12),
               o4 = bin.add(thick_b, 12);
  writeBytes(dir + "/t.bin", bin.bytes);
  std::string json = R"({"asset":{"version":"2.0"},"buffers":[{"uri":"t.bin","byteLength":@LEN@}],
    "bufferViews":[{"buffer":0,"byteOffset":@O0@,"byteLength":36},{"buffer":0,"byteOffset":@O1@,"byteLength":4},
                   {"buffer":0,"byteOffset":@O2@,"byteLength":4},{"buffer":0,"byteOffset":@O3@,"byteLength":12},
                   {"buffer":0,"byteOffset":@O4@,"byteLength":12}],
    "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},
                 {"bufferView":1,"componentType":5123,"count":2,"type":"SCALAR"},
                 {"bufferView":2,"componentType":5123,"count":2,"type":"SCALAR"},
                 {"bufferView":3,"componentType":5126,"count":3,"type":"SCALAR"},
                 {"bufferView":4,"componentType":5126,"count":3,"type":"SCALAR"}],
    "meshes":[{"primitives":[{"attributes":{"POSITION":0,"_THICKNESS":3},"indices":1,"mode":1},
                             {"attributes":{"POSITION":0,"_THICKNESS":4},"indices":2,"mode":1}]}],
    "nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]})";
  json = replaceAll(json, "@LEN@", std::to_string(bin.bytes.size()));
  json = replaceAll(json, "@O0@", std::to_string(o0));
  json = replaceAll(json, "@O1@", std::to_string(o1));
  json = replaceAll(json, "@O2@", std::to_string(o2));
  json = replaceAll(json, "@O3@", std::to_string(o3));
  json = replaceAll(json, "@O4@", std::to_string(o4));
  writeText(dir + "/t.gltf", json);
  SceneData s;
  const Error e = importGltf(dir + "/t.gltf", s);
  ASSERT_TRUE(e.ok()) << e.message;
  const Mesh& m = s.meshes[0].mesh;
  EXPECT_EQ(m.vertexCount(), 3u);  // one vertex set: both primitives use the same accessors
  EXPECT_EQ(m.edges, (std::vector<uint32_t>{0, 1, 1, 2}));
  EXPECT_EQ(m.edge_thickness, (std::vector<float>{0.5f, 0.5f}));  // (0.5+0.5)/2 and (0.25+0.75)/2
}

// a triangle (material 0), a line (material 1) and a point (no material) in one mesh: each keeps
// its primitive as its group, and a flattened scene gives each its material
TEST(GltfImport, EdgesAndPointsKeepTheirPrimitivesMaterial) {
  const std::string dir = makeDir("prim_groups");
  Bin bin;
  const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint16_t tri[] = {0, 1, 2, 0}, line[] = {0, 1}, point[] = {2, 0};
  const size_t o0 = bin.add(pos, sizeof(pos)), o1 = bin.add(tri, 8), o2 = bin.add(line, 4), o3 = bin.add(point, 4);
  writeBytes(dir + "/g.bin", bin.bytes);
  std::string json = R"({"asset":{"version":"2.0"},"buffers":[{"uri":"g.bin","byteLength":@LEN@}],
    "bufferViews":[{"buffer":0,"byteOffset":@O0@,"byteLength":36},{"buffer":0,"byteOffset":@O1@,"byteLength":6},
                   {"buffer":0,"byteOffset":@O2@,"byteLength":4},{"buffer":0,"byteOffset":@O3@,"byteLength":2}],
    "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},
                 {"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"},
                 {"bufferView":2,"componentType":5123,"count":2,"type":"SCALAR"},
                 {"bufferView":3,"componentType":5123,"count":1,"type":"SCALAR"}],
    "materials":[{"name":"a"},{"name":"b"}],
    "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0},
                             {"attributes":{"POSITION":0},"indices":2,"mode":1,"material":1},
                             {"attributes":{"POSITION":0},"indices":3,"mode":0}]}],
    "nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]})";
  json = replaceAll(json, "@LEN@", std::to_string(bin.bytes.size()));
  json = replaceAll(json, "@O0@", std::to_string(o0));
  json = replaceAll(json, "@O1@", std::to_string(o1));
  json = replaceAll(json, "@O2@", std::to_string(o2));
  json = replaceAll(json, "@O3@", std::to_string(o3));
  writeText(dir + "/g.gltf", json);
  SceneData s;
  const Error e = importGltf(dir + "/g.gltf", s);
  ASSERT_TRUE(e.ok()) << e.message;
  const Mesh& m = s.meshes[0].mesh;
  EXPECT_EQ(m.edge_groups, (std::vector<uint32_t>{1}));
  EXPECT_EQ(m.point_groups, (std::vector<uint32_t>{2}));
  const Mesh flat = flattenScene(s);
  EXPECT_EQ(flat.triangle_groups, (std::vector<uint32_t>{0}));
  EXPECT_EQ(flat.edge_groups, (std::vector<uint32_t>{1}));
  EXPECT_EQ(flat.point_groups, (std::vector<uint32_t>{kNoMaterial}));
}

TEST(GltfImport, NonIndexedPrimitiveUsesVerticesInOrder) {
  SquareGltf g;
  g.pos_count = "3";
  g.indices = "-1";
  SceneData s;
  const Error e = importGltf(g.write(makeDir("nonindexed")), s);
  ASSERT_TRUE(e.ok()) << e.message;
  EXPECT_EQ(s.meshes[0].mesh.triangles, (std::vector<uint32_t>{0, 1, 2}));
}

TEST(GltfImport, AnyIndexTypeNormalizedColoursAndMaterialFactor) {
  // ubyte indices, ubyte-normalized RGBA COLOR_0, a material with a base colour factor, TRS node
  const std::string dir = makeDir("types");
  Bin bin;
  const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint8_t idx[] = {0, 1, 2};
  const uint8_t col[] = {255, 0, 0, 255, 0, 255, 0, 255, 51, 102, 255, 255};
  const size_t o_pos = bin.add(pos, sizeof(pos)), o_idx = bin.add(idx, sizeof(idx)), o_col = bin.add(col, sizeof(col));
  writeBytes(dir + "/t.bin", bin.bytes);
  std::string json = R"({"asset":{"version":"2.0"},
    "buffers":[{"uri":"t.bin","byteLength":@LEN@}],
    "bufferViews":[{"buffer":0,"byteOffset":@OPOS@,"byteLength":36},{"buffer":0,"byteOffset":@OIDX@,"byteLength":3},
                   {"buffer":0,"byteOffset":@OCOL@,"byteLength":12}],
    "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},
                 {"bufferView":1,"componentType":5121,"count":3,"type":"SCALAR"},
                 {"bufferView":2,"componentType":5121,"normalized":true,"count":3,"type":"VEC4"}],
    "materials":[{"name":"half","pbrMetallicRoughness":{"baseColorFactor":[0.5,1,1,1]}}],
    "meshes":[{"primitives":[{"attributes":{"POSITION":0,"COLOR_0":2},"indices":1,"material":0}]}],
    "nodes":[{"mesh":0,"translation":[1,2,3],"rotation":[0,0,0.7071067811865476,0.7071067811865476],"scale":[2,2,2]}],
    "scenes":[{"nodes":[0]}]})";
  json = replaceAll(json, "@LEN@", std::to_string(bin.bytes.size()));
  json = replaceAll(json, "@OPOS@", std::to_string(o_pos));
  json = replaceAll(json, "@OIDX@", std::to_string(o_idx));
  json = replaceAll(json, "@OCOL@", std::to_string(o_col));
  writeText(dir + "/t.gltf", json);
  SceneData s;
  const Error e = importGltf(dir + "/t.gltf", s);
  ASSERT_TRUE(e.ok()) << e.message;
  const Mesh& m = s.meshes[0].mesh;
  EXPECT_EQ(m.triangles, (std::vector<uint32_t>{0, 1, 2}));
  // COLOR_0 as read; the material's factor only in the baked colours
  ASSERT_EQ(m.colors.size(), 3u);
  EXPECT_NEAR(m.colors[0].r, 1.0f, 1e-6f);
  EXPECT_NEAR(m.colors[2].r, 51.0f / 255.0f, 1e-6f);
  const std::vector<glm::vec3> baked = bakedMaterialColors(s, s.meshes[0]);
  ASSERT_EQ(baked.size(), 3u);
  EXPECT_NEAR(baked[0].r, 0.5f, 1e-6f);  // factor 0.5 x 1
  EXPECT_NEAR(baked[1].g, 1.0f, 1e-6f);
  EXPECT_NEAR(baked[2].r, 0.5f * 51.0f / 255.0f, 1e-6f);
  EXPECT_NEAR(baked[2].g, 102.0f / 255.0f, 1e-6f);
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_EQ(s.materials[0].name, "half");
  // T * R(90 deg about z) * S(2): (1,0,0) -> (0,2,0) + (1,2,3)
  const glm::vec3 p(s.nodes[0].local * glm::vec4(1, 0, 0, 1));
  EXPECT_NEAR(p.x, 1.0f, 1e-5f);
  EXPECT_NEAR(p.y, 4.0f, 1e-5f);
  EXPECT_NEAR(p.z, 3.0f, 1e-5f);
}

TEST(GltfImport, AveragesTheBaseColourTextureInLinearSpace) {
  // a 2x2 24-bit BMP: two white texels, two texels of sRGB 128; linear mean = (1 + 0.2158) / 2
  const std::string dir = makeDir("texture");
  std::vector<unsigned char> bmp = {'B', 'M', 70, 0, 0, 0, 0, 0, 0, 0, 54, 0, 0, 0, 40, 0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 1, 0, 24, 0,
                                    0, 0, 0, 0, 16, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  const unsigned char rows[] = {255, 255, 255, 128, 128, 128, 0, 0, 255, 255, 255, 128, 128, 128, 0, 0};
  bmp.insert(bmp.end(), rows, rows + sizeof(rows));
  writeBytes(dir + "/tex.bmp", bmp);
  SquareGltf g;
  g.extra = R"(,"images":[{"uri":"tex.bmp"}],"textures":[{"source":0}],
      "materials":[{"pbrMetallicRoughness":{"baseColorFactor":[1,0.5,1,1],"baseColorTexture":{"index":0}}}])";
  g.primitive_extra = R"(,"material":0)";
  SceneData s;
  const Error e = importGltf(g.write(dir), s);
  ASSERT_TRUE(e.ok()) << e.message;
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_TRUE(s.materials[0].textured);
  const float lin128 = std::pow((128.0f / 255.0f + 0.055f) / 1.055f, 2.4f);
  const float mean = 0.5f * (1.0f + lin128);
  EXPECT_NEAR(s.materials[0].average_texel_color.r, mean, 1e-5f);
  EXPECT_NEAR(s.materials[0].average_texel_color.b, mean, 1e-5f);
  EXPECT_TRUE(s.meshes[0].mesh.colors.empty());  // no COLOR_0: the material is kept, not baked in
  bakeMaterialColors(s);
  const Mesh& m = s.meshes[0].mesh;
  ASSERT_EQ(m.colors.size(), 4u);
  EXPECT_NEAR(m.colors[3].r, mean, 1e-5f);
  EXPECT_NEAR(m.colors[3].g, 0.5f * mean, 1e-5f);
  // the image is kept (bytes) and decoded to 2 x 2 RGBA (each row: a white texel, then sRGB 128)
  ASSERT_EQ(s.images.size(), 1u);
  EXPECT_EQ(s.images[0].encoded, bmp);
  EXPECT_EQ(s.images[0].width, 2);
  EXPECT_EQ(s.images[0].height, 2);
  ASSERT_EQ(s.images[0].rgba8.size(), 16u);
  EXPECT_EQ(s.images[0].rgba8[0], 255);
  EXPECT_EQ(s.images[0].rgba8[4], 128);
  EXPECT_EQ(s.images[0].rgba8[7], 255);
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_EQ(s.textures[0].image, 0);
  EXPECT_EQ(s.materials[0].base_color_texture, 0);
}

TEST(GltfImport, WithoutScenesEveryParentlessNodeIsARootInOrder) {
  const std::string dir = makeDir("noscene");
  SquareGltf g;
  std::string path = g.write(dir);
  std::string json;
  {
    std::ifstream f(path);
    json.assign(std::istreambuf_iterator<char>(f), {});
  }
  json = replaceAll(json, R"("nodes":[{"mesh":0}],
      "scenes":[{"nodes":[0]}],"scene":0)",
                    R"("nodes":[{"name":"a","children":[2]},{"name":"b","mesh":0},{"name":"c","mesh":0}])");
  writeText(path, json);
  SceneData s;
  const Error e = importGltf(path, s);
  ASSERT_TRUE(e.ok()) << e.message;
  EXPECT_EQ(s.roots, (std::vector<int32_t>{0, 1}));
  EXPECT_EQ(s.nodes[2].parent, 0);
  EXPECT_EQ(objectNodes(s), (std::vector<int32_t>{2, 1}));  // pre-order from the roots
}

TEST(GltfImport, AcceptsRequiredMaterialOnlyExtensions) {
  SquareGltf g;
  g.extra = R"(,"extensionsUsed":["KHR_texture_transform","KHR_materials_sheen"],"extensionsRequired":["KHR_texture_transform"])";
  SceneData s;
  const Error e = importGltf(g.write(makeDir("ext_ok")), s);
  EXPECT_TRUE(e.ok()) << e.message;
}

TEST(GltfImport, RefusesRequiredGeometryCompression) {
  SquareGltf g;
  g.extra = R"(,"extensionsUsed":["KHR_draco_mesh_compression"],"extensionsRequired":["KHR_draco_mesh_compression"])";
  const std::string path = g.write(makeDir("ext_draco"));
  const Error e = importExpectingError(path);
  EXPECT_EQ(e.status, Status::kUnsupported);
  EXPECT_TRUE(contains(e.message, path + ": requires extension KHR_draco_mesh_compression")) << e.message;
}

TEST(GltfImport, MissingFile) {
  const Error e = importExpectingError("/nonexistent/model.glb");
  EXPECT_EQ(e.status, Status::kIoError);
  EXPECT_TRUE(contains(e.message, "/nonexistent/model.glb: cannot open file")) << e.message;
}

TEST(GltfImport, TruncatedExternalBuffer) {
  SquareGltf g;
  g.byte_length = "600";  // the .bin holds 60
  const std::string path = g.write(makeDir("short_bin"));
  const Error e = importExpectingError(path);
  EXPECT_EQ(e.status, Status::kCorrupt);
  EXPECT_TRUE(contains(e.message, path + ": truncated or wrong-size buffer")) << e.message;
  EXPECT_TRUE(contains(e.message, "square.bin")) << e.message;
}

TEST(GltfImport, TruncatedGlb) {
  const std::string dir = makeDir("short_glb");
  SceneData s;
  ASSERT_TRUE(importGltf(SquareGltf().write(dir), s).ok());
  ASSERT_TRUE(exportGlb(dir + "/full.glb", s).ok());
  std::vector<unsigned char> bytes = readBytes(dir + "/full.glb");
  ASSERT_GT(bytes.size(), 40u);
  bytes.resize(bytes.size() - 10);
  writeBytes(dir + "/cut.glb", bytes);
  Error e = importExpectingError(dir + "/cut.glb");
  EXPECT_EQ(e.status, Status::kCorrupt);
  EXPECT_TRUE(contains(e.message, dir + "/cut.glb: truncated GLB: the header says")) << e.message;
  bytes.resize(8);
  writeBytes(dir + "/cut.glb", bytes);
  e = importExpectingError(dir + "/cut.glb");
  EXPECT_EQ(e.status, Status::kCorrupt);
  EXPECT_TRUE(contains(e.message, "truncated GLB: 8 bytes")) << e.message;
}

TEST(GltfImport, AccessorOutOfRange) {
  SquareGltf g;
  g.indices = "9";
  const std::string path = g.write(makeDir("acc_oor"));
  const Error e = importExpectingError(path);
  // tinygltf checks primitive accessor references itself while parsing; its words are kept
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_TRUE(contains(e.message, path + ": invalid reference: primitive indices accessor out of bounds")) << e.message;
}

TEST(GltfImport, BufferViewOutOfRange) {
  SquareGltf g;
  g.extra = R"(,"materials":[])";
  const std::string dir = makeDir("bv_oor");
  std::string path = g.write(dir);
  std::ifstream f(path);
  std::string json((std::istreambuf_iterator<char>(f)), {});
  json = replaceAll(json, R"({"bufferView":0,"componentType":5126)", R"({"bufferView":7,"componentType":5126)");
  writeText(path, json);
  const Error e = importExpectingError(path);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_TRUE(contains(e.message, path + ": ")) << e.message;
  EXPECT_TRUE(contains(e.message, "buffer view 7 out of range")) << e.message;
}

TEST(GltfImport, BufferViewBeyondItsBuffer) {
  SquareGltf g;
  const std::string dir = makeDir("bv_past");
  std::string path = g.write(dir);
  std::ifstream f(path);
  std::string json((std::istreambuf_iterator<char>(f)), {});
  json = replaceAll(json, R"({"buffer":0,"byteOffset":48,"byteLength":12})", R"({"buffer":0,"byteOffset":52,"byteLength":12})");
  writeText(path, json);
  const Error e = importExpectingError(path);
  EXPECT_EQ(e.status, Status::kCorrupt);
  EXPECT_TRUE(contains(e.message, path + ": buffer view 1 (bytes 52 to 64) is out of range of buffer 0 (60 bytes)")) << e.message;
}

TEST(GltfImport, AccessorReadingPastItsBufferView) {
  SquareGltf g;
  g.pos_count = "5";  // 60 bytes from a 48-byte view
  const std::string path = g.write(makeDir("acc_past"));
  const Error e = importExpectingError(path);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_TRUE(contains(e.message, path + ": mesh 0 primitive 0 POSITION: accessor 0 reads past the end of buffer view 0"))
      << e.message;
}

TEST(GltfImport, IndexNotBelowVertexCount) {
  SquareGltf g;
  g.index_data = {0, 1, 2, 1, 4, 2};
  const std::string path = g.write(makeDir("idx_oor"));
  const Error e = importExpectingError(path);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_TRUE(contains(e.message, path + ": mesh 0 primitive 0: index 4 is 4, not below the vertex count 4")) << e.message;
}

TEST(GltfImport, NanAndInfiniteCoordinates) {
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    SquareGltf g;
    g.positions[7] = bad;  // vertex 2, y
    const std::string path = g.write(makeDir("nan"));
    const Error e = importExpectingError(path);
    EXPECT_EQ(e.status, Status::kInvalidMesh);
    EXPECT_TRUE(contains(e.message, path + ": mesh 0 primitive 0 POSITION: accessor 0 element 2 has a NaN or infinite coordinate"))
        << e.message;
  }
}

TEST(GltfImport, UnsupportedMode) {
  SquareGltf g;
  g.mode = "7";
  const std::string path = g.write(makeDir("mode7"));
  const Error e = importExpectingError(path);
  EXPECT_EQ(e.status, Status::kUnsupported);
  EXPECT_TRUE(contains(e.message, path + ": mesh 0 primitive 0: unsupported primitive mode 7")) << e.message;
}

TEST(GltfImport, RefusesDotDotEscape) {
  const std::string outer = makeDir("escape");
  const std::string inner = makeDir("escape/inner");
  SquareGltf g;
  g.write(outer);  // square.bin next to the outer folder: it exists, and must still not be read
  g.uri = "../square.bin";
  const std::string path = g.write(inner);
  const Error e = importExpectingError(path);
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_TRUE(contains(e.message, path + ": external URI '../square.bin' escapes the glTF file's folder")) << e.message;
  // percent-encoded dots are decoded first and refused the same way
  g.uri = "%2e%2e/square.bin";
  g.write(inner);
  const Error e2 = importExpectingError(path);
  EXPECT_TRUE(contains(e2.message, "escapes the glTF file's folder")) << e2.message;
}

TEST(GltfImport, RefusesAbsoluteUri) {
  const std::string dir = makeDir("absolute");
  SquareGltf g;
  g.write(dir);
  g.uri = dir + "/square.bin";  // exists, but absolute
  const std::string path = g.write(dir);
  const Error e = importExpectingError(path);
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_TRUE(contains(e.message, path + ": external URI '" + dir + "/square.bin' is an absolute path")) << e.message;
}

TEST(GltfImport, MalformedJsonIsAParseError) {
  const std::string dir = makeDir("badjson");
  writeText(dir + "/bad.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [ {\"mesh\": ");
  const Error e = importExpectingError(dir + "/bad.gltf");
  EXPECT_EQ(e.status, Status::kParseError);
  EXPECT_TRUE(contains(e.message, dir + "/bad.gltf: cannot parse glTF")) << e.message;
}

namespace {

SceneData sampleScene() {
  SceneData s;
  MeshData md;
  md.name = "thing";
  Mesh& m = md.mesh;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 2, 2}, {3, 2, 2}, {5, 5, 5}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {1, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.25f, 0.5f, 0.75f}, {1, 1, 1}, {0, 0, 0}, {0.1f, 0.2f, 0.3f}};
  m.triangles = {0, 1, 2, 0, 2, 3};
  m.edges = {4, 5};
  m.edge_thickness = {0.125f};
  m.points = {6};
  s.meshes.push_back(md);
  NodeData root, child, other;
  root.name = "root";
  root.children = {1};
  root.local = glm::translate(glm::mat4(1.0f), glm::vec3(1, 2, 3));
  child.name = "child";
  child.parent = 0;
  child.mesh = 0;
  child.local = glm::scale(glm::rotate(glm::mat4(1.0f), 0.3f, glm::vec3(0, 1, 0)), glm::vec3(2.0f));
  other.name = "other";
  other.mesh = 0;
  s.nodes = {root, child, other};
  s.roots = {0, 2};
  return s;
}

}  // namespace

TEST(GltfExport, RoundTripKeepsHierarchyAndGeometryExactly) {
  const SceneData s = sampleScene();
  const std::string path = makeDir("export") + "/scene.glb";
  ASSERT_TRUE(exportGlb(path, s).ok());
  SceneData r;
  const Error e = importGltf(path, r);
  ASSERT_TRUE(e.ok()) << e.message;
  ASSERT_EQ(r.nodes.size(), 3u);
  EXPECT_EQ(r.roots, s.roots);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(r.nodes[i].name, s.nodes[i].name);
    EXPECT_EQ(r.nodes[i].parent, s.nodes[i].parent);
    EXPECT_EQ(r.nodes[i].children, s.nodes[i].children);
    EXPECT_EQ(r.nodes[i].mesh, s.nodes[i].mesh);
    EXPECT_EQ(r.nodes[i].local, s.nodes[i].local);
  }
  ASSERT_EQ(r.meshes.size(), 1u);
  const Mesh& a = s.meshes[0].mesh;
  const Mesh& b = r.meshes[0].mesh;
  EXPECT_EQ(r.meshes[0].name, "thing");
  EXPECT_EQ(b.positions, a.positions);  // shared vertices: triangles, lines and points use one set
  EXPECT_EQ(b.normals, a.normals);
  EXPECT_EQ(b.colors, a.colors);
  EXPECT_EQ(b.triangles, a.triangles);
  EXPECT_EQ(b.edges, a.edges);
  EXPECT_EQ(b.edge_thickness, a.edge_thickness);
  EXPECT_EQ(b.points, a.points);
}

TEST(GltfExport, EdgesWithDisagreeingThicknessGetTheirOwnVertices) {
  SceneData s = sampleScene();
  Mesh& m = s.meshes[0].mesh;
  m.edges = {4, 5, 5, 6};
  m.edge_thickness = {0.125f, 0.5f};  // vertex 5 is on both edges
  const std::string path = makeDir("export2") + "/scene.glb";
  ASSERT_TRUE(exportGlb(path, s).ok());
  SceneData r;
  ASSERT_TRUE(importGltf(path, r).ok());
  const Mesh& b = r.meshes[0].mesh;
  ASSERT_EQ(b.edgeCount(), 2u);
  EXPECT_EQ(b.edge_thickness, m.edge_thickness);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(b.positions[b.edges[i]], m.positions[m.edges[i]]);
  EXPECT_EQ(b.triangles, m.triangles);
}

TEST(GltfExport, LodChainsRoundTripThroughMsftLod) {
  SceneData s = sampleScene();
  LodChain chain;
  LodLevel l0;
  l0.mesh = s.meshes[0].mesh;
  chain.levels.push_back(l0);
  LodLevel l1;
  l1.mesh.positions = {{0.5f, 0.5f, 0}, {2.5f, 2, 2}, {5, 5, 5}};
  l1.mesh.normals = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
  l1.mesh.colors = {{0.3f, 0.3f, 0.3f}, {0.5f, 0.5f, 0.5f}, {0.1f, 0.2f, 0.3f}};
  l1.mesh.edges = {0, 1};
  l1.mesh.edge_thickness = {0.7f};
  l1.mesh.points = {2};
  l1.cell_width = 1.5f;
  l1.max_error = 0.75f;
  l1.method = LodMethod::kFloatingHeaviest;
  chain.levels.push_back(l1);
  LodLevel l2;
  l2.mesh.positions = {{2, 2, 2}};
  l2.mesh.colors = {{0.4f, 0.4f, 0.4f}};
  l2.mesh.points = {0};
  l2.cell_width = 4.0f;
  l2.max_error = 3.25f;
  l2.method = LodMethod::kUniform;
  chain.levels.push_back(l2);
  const std::vector<const LodChain*> chains = {&chain};
  const std::string path = makeDir("lod") + "/lod.glb";
  ASSERT_TRUE(exportGlb(path, s, &chains).ok());

  // a plain import sees the level nodes as extra parentless nodes outside the scene
  SceneData plain;
  ASSERT_TRUE(importGltf(path, plain).ok());
  EXPECT_EQ(plain.nodes.size(), 3u + 2u * 2u);  // two mesh instances, two coarser levels each
  EXPECT_EQ(plain.roots, s.roots);
  EXPECT_EQ(objectNodes(plain), objectNodes(s));

  SceneData r;
  std::vector<LodChain> rc;
  const Error e = importGltfLods(path, r, rc);
  ASSERT_TRUE(e.ok()) << e.message;
  ASSERT_EQ(r.nodes.size(), s.nodes.size());
  ASSERT_EQ(r.meshes.size(), 1u);
  EXPECT_EQ(r.roots, s.roots);
  ASSERT_EQ(rc.size(), 1u);
  ASSERT_EQ(rc[0].levelCount(), 3u);
  for (size_t l = 0; l < 3; ++l) {
    const LodLevel& a = chain.levels[l];
    const LodLevel& b = rc[0].levels[l];
    EXPECT_EQ(b.cell_width, a.cell_width) << l;
    EXPECT_EQ(b.max_error, a.max_error) << l;
    EXPECT_EQ(b.method, a.method) << l;
    EXPECT_EQ(b.mesh.positions, a.mesh.positions) << l;
    EXPECT_EQ(b.mesh.triangles, a.mesh.triangles) << l;
    EXPECT_EQ(b.mesh.edges, a.mesh.edges) << l;
    EXPECT_EQ(b.mesh.edge_thickness, a.mesh.edge_thickness) << l;
    EXPECT_EQ(b.mesh.points, a.mesh.points) << l;
    EXPECT_EQ(b.mesh.colors, a.mesh.colors) << l;
    if (b.mesh.vertexCount() > 1) {
      EXPECT_GT(b.bounds.radius, 0.0f) << l;
    }
  }

  // MSFT_screencoverage: one value per level, decreasing, the last 0; value i = 2 r X / (w_{i+1} H)
  const std::vector<unsigned char> bytes = readBytes(path);
  uint32_t json_len;
  std::memcpy(&json_len, &bytes[12], 4);
  const std::string json(bytes.begin() + 20, bytes.begin() + 20 + json_len);
  const size_t at = json.find("\"MSFT_screencoverage\":[");
  ASSERT_NE(at, std::string::npos) << json;
  std::vector<double> cov;
  const char* p = json.c_str() + at + std::strlen("\"MSFT_screencoverage\":[");
  while (*p && *p != ']') {
    char* end;
    cov.push_back(std::strtod(p, &end));
    p = *end == ',' ? end + 1 : end;
  }
  ASSERT_EQ(cov.size(), 3u);
  const float r0 = rc[0].levels[0].bounds.radius;
  EXPECT_NEAR(cov[0], 2.0 * r0 / (1.5 * 1080.0), 1e-6);
  EXPECT_NEAR(cov[1], 2.0 * r0 / (4.0 * 1080.0), 1e-6);
  EXPECT_EQ(cov[2], 0.0);
  EXPECT_TRUE(contains(json, "\"extensionsUsed\":[\"MSFT_lod\"]")) << json;
}

TEST(GltfExport, MeshWithoutChainGetsOneLevel) {
  SceneData s = sampleScene();
  const std::string path = makeDir("lod1") + "/plain.glb";
  ASSERT_TRUE(exportGlb(path, s).ok());
  SceneData r;
  std::vector<LodChain> rc;
  ASSERT_TRUE(importGltfLods(path, r, rc).ok());
  ASSERT_EQ(rc.size(), 1u);
  ASSERT_EQ(rc[0].levelCount(), 1u);
  EXPECT_EQ(rc[0].levels[0].mesh.positions, s.meshes[0].mesh.positions);
}

TEST(SceneLoad, ObjBecomesOneNodeAndFlattenAppliesWorldTransforms) {
  const std::string dir = makeDir("load");
  writeText(dir + "/tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
  SceneData s;
  ASSERT_TRUE(loadScene(dir + "/tri.obj", s).ok());
  ASSERT_EQ(s.nodes.size(), 1u);
  EXPECT_EQ(s.nodes[0].name, "tri");
  EXPECT_EQ(s.roots, (std::vector<int32_t>{0}));
  EXPECT_EQ(s.meshes[0].mesh.triangleCount(), 1u);

  // two instances, one mirrored: winding flips back, normals follow the inverse transpose
  s.nodes.push_back(s.nodes[0]);
  s.nodes[1].local = glm::scale(glm::mat4(1.0f), glm::vec3(-1, 1, 1));
  s.roots.push_back(1);
  s.nodes[0].local = glm::translate(glm::scale(glm::mat4(1.0f), glm::vec3(1, 1, 4)), glm::vec3(0, 0, 1));
  const Mesh flat = flattenScene(s);
  ASSERT_EQ(flat.vertexCount(), 6u);
  ASSERT_EQ(flat.triangleCount(), 2u);
  EXPECT_EQ(flat.positions[0], glm::vec3(0, 0, 4));
  EXPECT_EQ(flat.positions[4], glm::vec3(-1, 0, 0));
  EXPECT_EQ(flat.normals[0], glm::vec3(0, 0, 1));
  EXPECT_EQ(flat.triangles, (std::vector<uint32_t>{0, 1, 2, 3, 5, 4}));
  for (size_t t = 0; t < 2; ++t) {  // both face +z (counter-clockwise seen from +z)
    const glm::vec3 a = flat.positions[flat.triangles[3 * t]], b = flat.positions[flat.triangles[3 * t + 1]],
                    c = flat.positions[flat.triangles[3 * t + 2]];
    EXPECT_GT(glm::cross(b - a, c - a).z, 0.0f) << t;
  }
  EXPECT_EQ(loadScene(dir + "/tri.ply", s).status, Status::kUnsupported);
}

TEST(GltfImport, CorruptedGlbNeverCrashes) {
  // every truncation and a byte overwrite at every offset of a small GLB: each import either
  // succeeds with a valid scene or returns an error naming the file
  const std::string dir = makeDir("corrupt");
  ASSERT_TRUE(exportGlb(dir + "/good.glb", sampleScene()).ok());
  const std::vector<unsigned char> good = readBytes(dir + "/good.glb");
  ASSERT_GT(good.size(), 100u);
  const std::string path = dir + "/bad.glb";
  size_t failures = 0;
  auto check = [&](const std::vector<unsigned char>& bytes) {
    writeBytes(path, bytes);
    SceneData s;
    const Error e = importGltf(path, s);
    if (!e.ok()) {
      ++failures;
      EXPECT_EQ(e.message.rfind(path + ": ", 0), 0u) << e.message;
    } else {
      EXPECT_TRUE(validateSceneData(s, path).ok());
    }
  };
  size_t truncations = 0;
  for (size_t n = 0; n < good.size(); n += 3, ++truncations)
    check(std::vector<unsigned char>(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(n)));
  EXPECT_EQ(failures, truncations);  // every truncation is refused
  for (unsigned char value : {0x00, 0x39, 0xFF})
    for (size_t i = value == 0xFF ? 0 : value % 4; i < good.size(); i += value == 0xFF ? 1 : 4) {
      std::vector<unsigned char> bytes = good;
      bytes[i] = value;
      check(bytes);
    }
}

namespace {

// the square with one edit of its JSON text
std::string editedSquare(const std::string& dir, const std::string& from, const std::string& to) {
  const std::string path = SquareGltf().write(makeDir(dir));
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string edited = replaceAll(text, from, to);
  EXPECT_NE(edited, text) << "the edit '" << from << "' found nothing";
  writeText(path, edited);
  return path;
}

}  // namespace

TEST(GltfImport, HostileNumbersAreRefusedNotNarrowed) {
  // tinygltf narrows sizes into int and converts doubles into size_t: 2^32 + 1 would read as 1 and
  // 1e300 as 0, silently; each case must be refused naming the element and key
  const std::string pos = R"("bufferView":0,"componentType":5126,"count":4,"type":"VEC3")";
  const std::string sparse = R"(,"sparse":{"count":@N@,"indices":{"bufferView":1,"componentType":5123},"values":{"bufferView":0}})";
  const struct {
    std::string from, to, expect;
  } cases[] = {
      {"\"count\":4,", "\"count\":4294967297,", "accessor 0: \"count\" must be a whole number from 1 to 2^32 - 1"},
      {"\"bufferView\":0,\"componentType\":5126", "\"bufferView\":0,\"byteOffset\":1e300,\"componentType\":5126",
       "accessor 0: \"byteOffset\" must be a whole number"},
      {"\"byteOffset\":48", "\"byteOffset\":-48", "bufferView 1: \"byteOffset\" must be a whole number"},
      {pos, pos + replaceAll(sparse, "@N@", "-5"), "accessor 0: sparse \"count\" must be a whole number from 1"},
      {pos, pos + replaceAll(sparse, "@N@", "0"), "accessor 0: sparse \"count\" must be a whole number from 1"},
      {pos, pos + replaceAll(sparse, "@N@", "2147483648"), "accessor 0: sparse \"count\" 2147483648 exceeds the accessor's count 4"},
      {pos, pos + replaceAll(sparse, "@N@", "4294967297"), "accessor 0: sparse \"count\" must be a whole number"},
  };
  int i = 0;
  for (const auto& c : cases) {
    const std::string path = editedSquare("hostile_number_" + std::to_string(i++), c.from, c.to);
    const Error e = importExpectingError(path);
    EXPECT_EQ(e.status, Status::kParseError) << c.to;
    EXPECT_TRUE(contains(e.message, path + ": " + c.expect)) << e.message;
  }
}

TEST(GltfImport, DeeplyNestedJsonIsRefusedBeforeParsing) {
  // 20,000 nested arrays in a 40 KB file once overflowed the stack inside the parser
  SquareGltf g;
  g.extra = ",\"extras\":" + std::string(20000, '[') + std::string(20000, ']');
  const std::string path = g.write(makeDir("deep_json"));
  const Error e = importExpectingError(path);
  EXPECT_EQ(e.status, Status::kParseError);
  EXPECT_TRUE(contains(e.message, path + ": JSON nested deeper than 64 levels")) << e.message;
}

TEST(GltfImport, AccessorWithoutBufferViewIsCappedByBytes) {
  // an accessor without a buffer view holds zeros: its count alone once asked for gigabytes
  const std::string path = editedSquare("unbacked", R"("bufferView":0,"componentType":5126,"count":4,)",
                                        R"("componentType":5126,"count":16777216,)");
  const Error e = importExpectingError(path);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_TRUE(contains(e.message, "has no buffer view and an implausible count 16777216")) << e.message;
}
